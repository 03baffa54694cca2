//! `vmc-twin lobes --shard I/N --shard-dir DIR` (with or without `--controller`) and the merge
//! of its shards.
//!
//! The work items are the spindle speeds of `--rpm`, in order; shard `I/N` computes the block
//! [`crate::shard::Shard::block`] of them. The semi-discretisation traces the boundary in runs of
//! [`TRACE_RUN`] speeds that start afresh at fixed places of the whole list, and a block is
//! traced from the start of its first run ([`crate::dynamics::milling::MillingSdm::trace_block_at`]),
//! so a shard's points are bit-identical to the same speeds' points of the unsharded command;
//! the zero-order and time-domain methods treat each speed on its own. A shard's folder holds:
//! - `shard.json`, the manifest ([`ShardManifest`], command `lobes`; work ids `rpm N`);
//! - `lobes.jsonl`: one line per speed of the block ([`SpeedPoints`]): the tool's lobe point,
//!   or the open- and closed-loop points with a controller, `null` where no boundary lies in
//!   the searched range.
//!
//! The merge reads the points in the order of the speeds, checks that they are the list's
//! speeds, and prints and writes them with the functions of the unsharded command: the report
//! and the CSV are bit-identical to the unsharded run's.

use std::io::Write;
use std::ops::Range;
use std::path::Path;

use anyhow::{bail, Context, Result};
use serde::{Deserialize, Serialize};

use super::control::{self, ControlLobesConfig, ControlLobesHead};
use super::lobes::{self as tool_lobes, LobesConfig, LobesHead, LobesOutputs, ShardOutput};
use super::VERSION;
use crate::dynamics::milling::TRACE_RUN;
use crate::dynamics::{LobePoint, Resolution};
use crate::files;
use crate::shard::MergeConfig;
use crate::shard::{InputFingerprint, ShardManifest, MANIFEST_FILE, MANIFEST_FORMAT};

/// Name of the command in a shard's manifest.
pub const COMMAND: &str = "lobes";

/// Name of a lobes shard's points (one JSON object per speed and line).
pub const POINTS_FILE: &str = "lobes.jsonl";

/// The CSV the merge writes when the shards were given no `--out`.
pub const DEFAULT_CSV: &str = "lobes.csv";

/// The lobes a shard computes: of a tool, or of the blade without and with a controller.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
enum Head {
    /// `lobes [--tool FILE]`.
    Tool(LobesHead),
    /// `lobes --controller FILE`.
    Controller(ControlLobesHead),
}

/// What the merge needs besides the shards' points (the manifest's header).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
struct Header {
    /// The CSV as given to `--out`: the merge writes a file of that name.
    csv: Option<String>,
    /// What the report says besides the points.
    lobes: Head,
}

impl Header {
    /// Every speed asked for, rpm, in order.
    fn speeds_rpm(&self) -> &[f64] {
        match &self.lobes {
            Head::Tool(h) => &h.speeds_rpm,
            Head::Controller(h) => &h.speeds_rpm,
        }
    }

    /// Lobe points per speed: 1 for a tool, 2 (open and closed loop) with a controller.
    fn curves(&self) -> usize {
        match self.lobes {
            Head::Tool(_) => 1,
            Head::Controller(_) => 2,
        }
    }
}

/// One line of `lobes.jsonl`: a speed and its lobe points.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SpeedPoints {
    /// The speed, rpm.
    pub spindle_rpm: f64,
    /// The point of each curve (the tool's; or open, then closed loop), `None` without a
    /// boundary in the searched range.
    pub points: Vec<Option<LobePoint>>,
}

/// Computes one shard of `lobes` (a tool's lobes) and writes it for `merge`.
///
/// # Errors
/// Outputs that may not be written, values the dynamics refuses.
pub fn lobes_shard(cfg: &LobesConfig, target: &ShardOutput, out: &mut dyn Write) -> Result<()> {
    let header = Header {
        csv: cfg.out.as_ref().map(|p| p.display().to_string()),
        lobes: Head::Tool(LobesHead::of(cfg)),
    };
    let arguments = [
        ("method", serde_json::to_string(&cfg.method)?),
        ("immersion", cfg.immersion.to_string()),
        ("milling direction", serde_json::to_string(&cfg.milling)?),
        ("resolution", resolution_argument(&cfg.resolution)),
    ];
    let compute = |block| {
        let points = tool_lobes::lobes_block(cfg, block)?;
        Ok(points.into_iter().map(|p| vec![p]).collect())
    };
    write_shard(target, cfg.force, &header, &arguments, compute, out)
}

/// Computes one shard of `lobes --controller` (open- and closed-loop lobes) and writes it for
/// `merge`.
///
/// # Errors
/// Outputs that may not be written, an unstable loop.
pub fn control_lobes_shard(
    cfg: &ControlLobesConfig,
    target: &ShardOutput,
    out: &mut dyn Write,
) -> Result<()> {
    let header = Header {
        csv: cfg.out.as_ref().map(|p| p.display().to_string()),
        lobes: Head::Controller(ControlLobesHead::of(cfg)),
    };
    let arguments = [("resolution", resolution_argument(&cfg.resolution))];
    let compute = |block| {
        let [open, closed] = control::lobes_block(cfg, block)?;
        Ok(open
            .into_iter()
            .zip(closed)
            .map(|(o, c)| vec![o, c])
            .collect())
    };
    write_shard(target, cfg.force, &header, &arguments, compute, out)
}

/// The resolution as a shard's argument: every field of the fixed count or of the rule, so
/// shards computed at different resolutions are refused by the merge.
fn resolution_argument(resolution: &Resolution) -> String {
    format!("{resolution:?}")
}

/// Writes a shard's points (computed by `compute` for its block of the speeds, one list of
/// points per speed) and then its manifest, and says what it covered.
fn write_shard(
    target: &ShardOutput,
    force: bool,
    header: &Header,
    arguments: &[(&str, String)],
    compute: impl FnOnce(Range<usize>) -> Result<Vec<Vec<Option<LobePoint>>>>,
    out: &mut dyn Write,
) -> Result<()> {
    let (shard, dir) = (target.shard, &target.dir);
    let speeds = header.speeds_rpm();
    let block = shard.block(speeds.len());
    let names = [MANIFEST_FILE, POINTS_FILE].map(String::from);
    files::prepare_output_folder(dir, &names, force)?;
    let mut inputs = vec![target.file.clone()];
    for (name, text) in arguments {
        inputs.push(InputFingerprint::of(name, "arguments", text.as_bytes()));
    }
    let list: Vec<String> = speeds.iter().map(f64::to_string).collect();
    inputs.push(InputFingerprint::of(
        "speeds",
        "arguments",
        list.join(",").as_bytes(),
    ));
    let mine = &speeds[block.clone()];
    let manifest = ShardManifest {
        format: MANIFEST_FORMAT,
        command: COMMAND.into(),
        shard,
        work_ids: mine.iter().map(|n| format!("rpm {n}")).collect(),
        work_total: speeds.len(),
        command_line: target.command_line.clone(),
        version: VERSION.into(),
        inputs,
        header: serde_json::to_value(header)?,
        results: Vec::new(),
    };
    let points = if mine.is_empty() {
        Vec::new()
    } else {
        compute(block.clone())?
    };
    files::write_atomic_with(&dir.join(POINTS_FILE), force, |w| {
        for (&spindle_rpm, points) in mine.iter().zip(points) {
            serde_json::to_writer(
                &mut *w,
                &SpeedPoints {
                    spindle_rpm,
                    points,
                },
            )?;
            w.write_all(b"\n")?;
        }
        Ok(())
    })?;
    // The manifest last: a folder with a manifest has its points.
    let path =
        crate::shard::integrity::write_manifest(dir, manifest, &[POINTS_FILE.to_string()], force)?;
    let covered = match (mine.first(), mine.last()) {
        (Some(a), Some(b)) => {
            // The trace of the block starts at the first speed of its run.
            let from = block.start - block.start % TRACE_RUN;
            let warm = if from < block.start && uses_trace(header) {
                format!(", traced from speed {} of the list", from + 1)
            } else {
                String::new()
            };
            format!("{a} to {b} rpm{warm}")
        }
        _ => "none: nothing to compute".into(),
    };
    writeln!(
        out,
        "lobes shard {shard}: {} of {} speeds ({covered}); wrote {}{}",
        mine.len(),
        speeds.len(),
        path.display(),
        if mine.is_empty() {
            format!(" and an empty {POINTS_FILE}")
        } else {
            format!(" and {POINTS_FILE}")
        }
    )?;
    Ok(())
}

/// Whether the shard's lobes are traced from speed to speed (semi-discretisation).
fn uses_trace(header: &Header) -> bool {
    match &header.lobes {
        Head::Tool(h) => h.method == crate::dynamics::Method::Sdm,
        Head::Controller(_) => true,
    }
}

/// Merges lobes shards (checked as a set, in shard order): prints the report and writes the
/// CSV in `cfg.out_dir` under the file name given to the shards' `--out` (`lobes.csv` without
/// one), and with `cfg.rrd` the recording, as the unsharded `lobes` does.
///
/// # Errors
/// A bad header, unreadable points, points of other speeds than the list's, outputs that may
/// not be written.
pub fn merge(
    cfg: &MergeConfig,
    first: &ShardManifest,
    dirs: &[&Path],
    out: &mut dyn Write,
) -> Result<()> {
    if cfg.print_runs || cfg.png.is_some() {
        bail!("--runs and --png are for campaign shards; these are lobes shards");
    }
    let header: Header =
        serde_json::from_value(first.header.clone()).context("the shards' header")?;
    let name = match &header.csv {
        Some(given) => Path::new(given)
            .file_name()
            .map(|n| n.to_string_lossy().to_string())
            .with_context(|| format!("the shards' --out `{given}` names no file"))?,
        None => DEFAULT_CSV.to_string(),
    };
    if let Some(rrd) = &cfg.rrd {
        crate::record::check_rrd_path(rrd, cfg.force)?;
    }
    let csv = files::prepare_output_folder(&cfg.out_dir, &[name], cfg.force)?;
    // One list per curve: the tool's, or open then closed loop.
    let mut curves = read_points(dirs, header.speeds_rpm(), header.curves())?.into_iter();
    let mut next = || curves.next().unwrap_or_default();
    let outputs = LobesOutputs {
        csv: csv.first().map(|p| p.as_path()),
        rrd: cfg.rrd.as_deref(),
        force: cfg.force,
    };
    match &header.lobes {
        Head::Tool(h) => tool_lobes::write_lobes(h, &next(), &outputs, out),
        Head::Controller(h) => {
            let (open, closed) = (next(), next());
            control::write_lobes(h, open, closed, &outputs, out)
        }
    }
}

/// The points of every speed, read from the shards' files in shard order, as one list per
/// curve without the speeds that have no boundary; the files must hold exactly `speeds` in
/// order, each with `curves` points.
fn read_points(dirs: &[&Path], speeds: &[f64], curves: usize) -> Result<Vec<Vec<LobePoint>>> {
    let mut expected = speeds.iter();
    let mut all: Vec<Vec<LobePoint>> = vec![Vec::new(); curves];
    let files = dirs.iter().map(|d| d.join(POINTS_FILE));
    super::for_each_shard_line(
        files,
        |r: SpeedPoints, at| {
            let n = r.spindle_rpm;
            match expected.next() {
                Some(&s) if s.to_bits() == n.to_bits() => {}
                Some(&s) => bail!("{}: speed {n} rpm, expected {s} rpm", at()),
                None => bail!("{}: speed {n} rpm beyond the shards' speeds", at()),
            }
            if r.points.len() != curves {
                bail!(
                    "{}: {} points per speed, these lobes have {curves}",
                    at(),
                    r.points.len()
                );
            }
            for (curve, p) in all.iter_mut().zip(r.points) {
                curve.extend(p);
            }
            Ok(())
        },
        |e| e,
    )?;
    if let Some(s) = expected.next() {
        bail!("the shard results hold no points for speed {s} rpm");
    }
    Ok(all)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_speed_s_points_round_trip_through_a_line_bit_for_bit() {
        let p = LobePoint {
            spindle_rpm: 7666.666666666667,
            critical_depth_mm: 0.1 + 0.2,
            chatter_frequency_hz: 1.0 / 3.0,
            kind: crate::dynamics::BoundaryKind::Flip,
            steps_per_period: Some(1280),
        };
        let line = SpeedPoints {
            spindle_rpm: p.spindle_rpm,
            points: vec![Some(p), None],
        };
        let text = serde_json::to_string(&line).unwrap();
        let back: SpeedPoints = serde_json::from_str(&text).unwrap();
        let q = back.points[0].unwrap();
        assert_eq!(q.critical_depth_mm.to_bits(), p.critical_depth_mm.to_bits());
        assert_eq!(
            q.chatter_frequency_hz.to_bits(),
            p.chatter_frequency_hz.to_bits()
        );
        assert_eq!(back, line);
    }

    #[test]
    fn a_line_written_before_the_steps_per_period_reads_as_none() {
        let old = r#"{"spindle_rpm":5000.0,"points":[{"spindle_rpm":5000.0,"critical_depth_mm":0.44,"chatter_frequency_hz":950.0,"kind":"Hopf"}]}"#;
        let back: SpeedPoints = serde_json::from_str(old).unwrap();
        let p = back.points[0].unwrap();
        assert_eq!(p.steps_per_period, None);
        assert_eq!(p.critical_depth_mm, 0.44);
    }
}
