//! `vmc-twin chatter`: which cutting moves of a milling program will chatter. Reads the program,
//! the stock and the tool, runs the check of [`crate::studies::chatter`], prints one line per cutting
//! move (line-numbered, as `check` does) and a summary, writes the CSV, and fails when a cut is
//! unstable.

use std::io::Write;
use std::path::PathBuf;

use anyhow::Result;

use crate::dynamics::Resolution;
use crate::files;
use crate::studies::chatter::stock_file::StockSpec;
use crate::studies::chatter::{self, ChatterOptions, ChatterReport, Cut, Verdict};
use vmc_gcode::interp::{self, InterpConfig};
use vmc_machine::milling::ToolDynamics;
use vmc_machine::program::ProgramError;
use vmc_machine::tools::TOOL_NUMBERS;

/// What to check, validated.
pub struct ChatterConfig {
    /// The G-code program.
    pub program: PathBuf,
    /// The stock, read from its file.
    pub stock: StockSpec,
    /// The stock file (for the report).
    pub stock_source: String,
    /// The tool and its tool-tip modes.
    pub tool: ToolDynamics,
    /// Where the tool came from (for the report).
    pub tool_source: String,
    /// Check settings (the grid from the command line, else the stock file, else D/32).
    pub options: ChatterOptions,
    /// CSV output.
    pub out: Option<PathBuf>,
    /// Overwrite an existing output file.
    pub force: bool,
    /// A Rerun recording to write: the lobes of the program's engagements with its cuts.
    pub rrd: Option<PathBuf>,
}

/// Interprets the program (coordinates as programmed: no machine work offsets; subroutine
/// files next to it; every tool number 0…999 is the cutter of `diameter_mm`, so that G41/G42
/// offset the path by its radius).
///
/// # Errors
/// An unreadable file, a syntax or semantic error (with its line).
pub fn load_moves(
    path: &std::path::Path,
    diameter_mm: f64,
) -> Result<Vec<interp::CanonMove>, ProgramError> {
    let file = path.display().to_string();
    let text = files::read_text(path).map_err(|err| ProgramError::Io {
        file: file.clone(),
        err,
    })?;
    let cfg = InterpConfig {
        subroutine_dirs: vec![path
            .parent()
            .unwrap_or(std::path::Path::new(""))
            .to_path_buf()],
        tool_diameters_mm: (0..TOOL_NUMBERS).map(|t| (t, diameter_mm)).collect(),
        ..InterpConfig::default()
    };
    interp::run_program(&text, &cfg).map_err(|err| ProgramError::Gcode { file, err })
}

/// Checks the program, prints the report, writes the CSV.
///
/// # Errors
/// An unreadable or invalid program, a stock the program never touches, a cut with the spindle
/// stopped, an output that may not be written; after the report, any unstable cut.
pub fn chatter(cfg: &ChatterConfig, out: &mut dyn Write) -> Result<()> {
    if let Some(path) = &cfg.out {
        files::check_writable(path, cfg.force)?;
    }
    if let Some(path) = &cfg.rrd {
        crate::record::check_rrd_path(path, cfg.force)?;
    }
    let file = cfg.program.display().to_string();
    let moves = load_moves(&cfg.program, cfg.tool.tool.diameter_mm)?;
    let report = chatter::check(&moves, &cfg.stock.stock, &cfg.tool, &cfg.options)
        .map_err(|e| anyhow::anyhow!("{file}: {e}"))?;
    // The report is printed and, with --rrd, also stored in the recording.
    let mut text = Vec::new();
    write_report(cfg, &report, &file, &mut text)?;
    out.write_all(&text)?;
    if let Some(path) = &cfg.out {
        files::write_atomic(path, chatter::report_csv(&report).as_bytes(), cfg.force)?;
        writeln!(out, "wrote {}", path.display())?;
    }
    if let Some(path) = &cfg.rrd {
        let (curves, cuts) = diagram(cfg, &report)?;
        let md = format!(
            "# vmc-twin chatter\n\nStability lobes (SDM, feed along X) of each engagement the \
             program has, with its cutting moves at (spindle speed, axial depth): green stable, \
             yellow marginal, red unstable. A cut above the curve of its engagement \
             chatters.\n\n```text\n{}```\n",
            String::from_utf8_lossy(&text)
        );
        let title = format!("vmc-twin chatter {file}");
        let bytes = crate::record::chatter::record_lobe_diagram(
            path, cfg.force, &title, &curves, &cuts, &md,
        )?;
        super::wrote_recording(out, path, bytes, "")?;
    }
    let unstable: Vec<String> = report
        .cuts
        .iter()
        .filter(|c| c.verdict == Verdict::Unstable)
        .map(|c| c.line.to_string())
        .collect();
    if unstable.is_empty() {
        writeln!(out, "no unstable cut")?;
        return Ok(());
    }
    const SHOWN: usize = 12;
    let more = if unstable.len() > SHOWN {
        format!(" and {} more", unstable.len() - SHOWN)
    } else {
        String::new()
    };
    anyhow::bail!(
        "{file}: {} of {} cuts would chatter (unstable) — line(s) {}{more}",
        unstable.len(),
        report.cuts.len(),
        unstable[..unstable.len().min(SHOWN)].join(", ")
    )
}

/// Speeds of the diagram's lobes, spread over half the program's lowest to 1.5 × its highest.
const DIAGRAM_SPEEDS: usize = 121;

/// The lobe curve of every engagement the program's cuts have (a_e/D at the top of its bin, as
/// the check judges it; up, down, or the lower of both for an entry) over a band of speeds around
/// the program's, and the cuts as points.
///
/// # Errors
/// Values the dynamics refuses.
fn diagram(
    cfg: &ChatterConfig,
    report: &ChatterReport,
) -> Result<(
    Vec<crate::record::chatter::LobeCurve>,
    Vec<crate::record::chatter::CutPoint>,
)> {
    use crate::dynamics::{lobes, LobePoint, Method, Milling};
    use crate::record::chatter::{CutPoint, LobeCurve};
    use crate::studies::chatter::Engagement;
    let judged: Vec<&Cut> = report
        .cuts
        .iter()
        .filter(|c| c.engagement != Engagement::Plunge)
        .collect();
    let (lo, hi) = judged.iter().fold((f64::INFINITY, 0.0f64), |(lo, hi), c| {
        (lo.min(c.spindle_rpm), hi.max(c.spindle_rpm))
    });
    if judged.is_empty() {
        return Ok((Vec::new(), Vec::new()));
    }
    let speeds: Vec<f64> = (0..DIAGRAM_SPEEDS)
        .map(|k| 0.5 * lo + (1.5 * hi - 0.5 * lo) * k as f64 / (DIAGRAM_SPEEDS - 1) as f64)
        .collect();
    let bin = cfg.options.immersion_bin;
    let group_of = |c: &Cut| {
        let b = ((c.immersion / bin - 1e-9).ceil().max(1.0)) as u32;
        (b, c.engagement)
    };
    let mut groups: Vec<(u32, Engagement)> = judged.iter().map(|c| group_of(c)).collect();
    groups.sort_by_key(|&(b, e)| (b, e.name()));
    groups.dedup();
    let cuts = judged
        .iter()
        .map(|c| CutPoint {
            spindle_rpm: c.spindle_rpm,
            axial_depth_mm: c.axial_depth_mm,
            class: match c.verdict {
                Verdict::Stable => 0,
                Verdict::Marginal => 1,
                _ => 2,
            },
            curve: groups.iter().position(|g| *g == group_of(c)).unwrap_or(0),
        })
        .collect();
    let t = &cfg.tool;
    let mut curves = Vec::new();
    for (b, engagement) in groups {
        let immersion = (f64::from(b) * bin).min(1.0);
        let millings: &[Milling] = match engagement {
            Engagement::Up => &[Milling::Up],
            Engagement::Entry => &[Milling::Up, Milling::Down],
            _ => &[Milling::Down],
        };
        let mut points: Vec<LobePoint> = Vec::new();
        for &m in millings {
            for p in lobes(Method::Sdm, &t.tool, &t.modes, immersion, m, &speeds)? {
                match points.iter_mut().find(|q| q.spindle_rpm == p.spindle_rpm) {
                    Some(q) if p.critical_depth_mm < q.critical_depth_mm => *q = p,
                    Some(_) => {}
                    None => points.push(p),
                }
            }
        }
        points.sort_by(|a, b| a.spindle_rpm.total_cmp(&b.spindle_rpm));
        curves.push(LobeCurve {
            name: format!("a_e/D {immersion:.3} {}", engagement.name()),
            points,
        });
    }
    Ok((curves, cuts))
}

/// The header, one line per cut and the totals.
fn write_report(
    cfg: &ChatterConfig,
    report: &ChatterReport,
    file: &str,
    out: &mut dyn Write,
) -> Result<()> {
    write_header(cfg, report, out)?;
    for c in &report.cuts {
        writeln!(out, "{file}: {}", cut_line(c))?;
    }
    writeln!(
        out,
        "checked {} feed moves ({} in material, {} samples): {} stable, {} marginal, {} unstable, {} plunge(s); {} stability keys, {} SDM evaluations",
        report.feed_moves,
        report.cuts.len(),
        report.samples,
        report.count(Verdict::Stable),
        report.count(Verdict::Marginal),
        report.count(Verdict::Unstable),
        report.count(Verdict::Plunge),
        report.stability_keys,
        report.stability_evaluations
    )?;
    Ok(())
}

fn write_header(cfg: &ChatterConfig, r: &ChatterReport, out: &mut dyn Write) -> Result<()> {
    let (b, t, o) = (&cfg.stock.stock, &cfg.tool, &cfg.options);
    writeln!(
        out,
        "vmc-twin chatter: {} on stock {} ({}: X{} Y{} Z{} … X{} Y{} Z{} mm), tool {} ({}), {} teeth, Ø{} mm",
        cfg.program.display(),
        cfg.stock_source,
        cfg.stock.name,
        b.min_mm[0],
        b.min_mm[1],
        b.min_mm[2],
        b.max_mm[0],
        b.max_mm[1],
        b.max_mm[2],
        t.name,
        cfg.tool_source,
        t.tool.teeth,
        t.tool.diameter_mm
    )?;
    writeln!(
        out,
        "method: Z-map {:.3} × {:.3} mm ({} × {} cells); SDM {}, a_e/D rounded up to bins of {}, depths searched to {:.3} mm; the worst sample of each move; unstable: margin a_p,lim/a_p < 1, marginal: < {}",
        r.grid_mm[0],
        r.grid_mm[1],
        r.cells[0],
        r.cells[1],
        match o.resolution {
            Resolution::Fixed(m) => format!("with {m} steps per tooth period"),
            Resolution::Converged(_) => "at the converged resolution (steps per tooth period chosen per speed and checked)".to_string(),
        },
        o.immersion_bin,
        r.max_depth_mm,
        o.marginal_below
    )?;
    Ok(())
}

/// `line N: G1 10000 rpm 800 mm/min a_e/D 0.150 down a_p 1.000 mm a_p,lim 1.234 mm margin 1.23 marginal`.
fn cut_line(c: &Cut) -> String {
    let lim = match (c.critical_depth_mm, c.critical_depth_is_bound) {
        (Some(d), false) => format!("{d:>7.3}"),
        (Some(d), true) => format!(">{d:.3}"),
        (None, _) => format!("{:>7}", "-"),
    };
    let margin = match (c.margin, c.critical_depth_is_bound) {
        (Some(m), false) => format!("{m:>5.2}"),
        (Some(m), true) => format!(">{m:.2}"),
        (None, _) => format!("{:>5}", "-"),
    };
    format!(
        "line {:>4}: {} {:>6} rpm {:>6} mm/min  a_e/D {:.3} {:<6} a_p {:.3} mm  a_p,lim {lim} mm  margin {margin}  {}",
        c.line,
        c.motion,
        c.spindle_rpm,
        c.feed_mm_per_min,
        c.immersion,
        c.engagement.name(),
        c.axial_depth_mm,
        c.verdict.name()
    )
}
