//! `vmc-twin cut`: one cut in the time domain — the tool-tip vibration and the cutting forces
//! of a cut from its steady vibration, the spectrum, the chatter frequency and the verdict,
//! with the semi-discretisation critical depth at the same speed for comparison.

use std::fmt::Write as _;
use std::io::Write;
use std::path::PathBuf;

use anyhow::Result;

use crate::dynamics::cut::{simulate_cut, CutOptions, CutSimulation, Verdict};
use crate::dynamics::{sdm_lowest_critical_depth, BoundaryKind, Cut, LobePoint, Milling};
use crate::files;
use crate::record;
use vmc_machine::milling::{cut_csv, kind_name, ToolDynamics};

/// What to simulate, validated.
pub struct CutConfig {
    /// The tool and its tool-tip modes.
    pub tool: ToolDynamics,
    /// Where the tool came from (for the report).
    pub tool_source: String,
    /// Speed, depth, immersion, feed and direction.
    pub cut: Cut,
    /// Steps per tooth period, horizon and disturbance.
    pub options: CutOptions,
    /// CSV output (time_s, x_um, y_um, fx_n, fy_n).
    pub out: Option<PathBuf>,
    /// Rerun recording.
    pub rrd: Option<PathBuf>,
    /// Overwrite existing output files.
    pub force: bool,
}

/// Simulates the cut, prints the report, writes the CSV and the recording.
///
/// # Errors
/// An output that may not be written, values the dynamics refuses.
pub fn cut(cfg: &CutConfig, out: &mut dyn Write) -> Result<()> {
    if let Some(path) = &cfg.out {
        files::check_writable(path, cfg.force)?;
    }
    if let Some(path) = &cfg.rrd {
        record::check_rrd_path(path, cfg.force)?;
    }
    let t = &cfg.tool;
    let sim = simulate_cut(&t.tool, &t.modes, &cfg.cut, &cfg.options)?;
    let c = &cfg.cut;
    let sdm = sdm_lowest_critical_depth(&t.tool, &t.modes, c.immersion, c.milling, c.spindle_rpm)?;
    let text = report(cfg, &sim, sdm.as_ref());
    out.write_all(text.as_bytes())?;
    if let Some(path) = &cfg.out {
        files::write_atomic(path, cut_csv(&sim).as_bytes(), cfg.force)?;
        writeln!(out, "wrote {}", path.display())?;
    }
    if let Some(path) = &cfg.rrd {
        // Spectra up to 3 × the highest mode (at least 5 tooth-passing harmonics).
        let f_max = t
            .modes
            .x
            .iter()
            .chain(&t.modes.y)
            .map(|m| m.frequency_hz)
            .fold(0.0, f64::max);
        let max_hz = (3.0 * f_max).max(5.0 / sim.period_s);
        let title = format!(
            "vmc-twin cut {} {} rpm {} mm {} {}",
            t.name,
            c.spindle_rpm,
            c.axial_depth_mm,
            c.immersion,
            milling_name(c.milling)
        );
        let md = format!("# vmc-twin cut\n\n```text\n{text}```\n");
        let bytes = record::dynamics::record_cut(path, cfg.force, &title, &sim, max_hz, &md)?;
        super::wrote_recording(out, path, bytes, "")?;
    }
    Ok(())
}

/// `up` or `down`.
pub fn milling_name(m: Milling) -> &'static str {
    match m {
        Milling::Up => "up",
        Milling::Down => "down",
    }
}

/// The printed report.
fn report(cfg: &CutConfig, sim: &CutSimulation, sdm: Option<&LobePoint>) -> String {
    let (t, c) = (&cfg.tool, &cfg.cut);
    let teeth = t.tool.teeth;
    let periods = sim.change_per_tooth_m.len();
    let mut s = String::new();
    let _ = writeln!(
        s,
        "vmc-twin cut: {} ({}), {teeth} teeth, helix {}°, {} rpm, a_p {} mm, a_e/D {}, f_z {} mm, {} milling",
        t.name,
        cfg.tool_source,
        t.tool.helix_deg,
        c.spindle_rpm,
        c.axial_depth_mm,
        c.immersion,
        c.feed_per_tooth_mm,
        milling_name(c.milling)
    );
    let _ = writeln!(
        s,
        "simulated {periods} tooth periods ({:.1} revolutions, {:.4} s) from the steady cut, {} steps per tooth period, {} axial disk(s)",
        periods as f64 / f64::from(teeth),
        periods as f64 * sim.period_s,
        cfg.options.steps_per_tooth,
        sim.disks
    );
    let growth = if sim.settled {
        format!(
            "the change per tooth period fell ×{:.1e} since the start: settled",
            sim.growth_from_start
        )
    } else {
        format!(
            "change per tooth period ×{:.3} from the second to the last quarter, ×{:.3e} since the start",
            sim.growth_ratio, sim.growth_from_start
        )
    };
    let tooth_hz = 1.0 / sim.period_s;
    match sim.verdict {
        Verdict::Chatter => {
            let _ = writeln!(
                s,
                "verdict: chatter (a disturbance of the steady cut grows: {growth})"
            );
            match (sim.chatter_frequency_hz(), sim.chatter_kind()) {
                (Some(f), Some(kind)) => {
                    let _ = writeln!(
                        s,
                        "chatter frequency: {f:.1} Hz ({}; tooth passing {tooth_hz:.1} Hz)",
                        kind_text(kind)
                    );
                }
                _ => {
                    let _ = writeln!(s, "chatter frequency: no peak near the modes");
                }
            }
        }
        Verdict::Stable => {
            let _ = writeln!(
                s,
                "verdict: stable (a disturbance of the steady cut dies out: {growth})"
            );
            let _ = writeln!(
                s,
                "chatter frequency: none (tooth passing {tooth_hz:.1} Hz)"
            );
        }
    }
    let [dx, dy, d] = sim.max_displacement_m();
    let _ = writeln!(
        s,
        "max vibration: {:.2} µm (|x| {:.2} µm, |y| {:.2} µm)",
        d * 1e6,
        dx * 1e6,
        dy * 1e6
    );
    let [fx, fy, f] = sim.max_force_n();
    let _ = writeln!(s, "max force: {f:.1} N (|Fx| {fx:.1} N, |Fy| {fy:.1} N)");
    match sdm {
        Some(p) => {
            let _ = writeln!(
                s,
                "SDM critical depth at {} rpm: {:.4} mm ({}, {:.1} Hz; converged, {} steps per tooth period); this depth is {:.1} % of it",
                c.spindle_rpm,
                p.critical_depth_mm,
                kind_name(p.kind),
                p.chatter_frequency_hz,
                p.steps_per_period.map_or_else(|| "-".to_string(), |m| m.to_string()),
                100.0 * c.axial_depth_mm / p.critical_depth_mm
            );
        }
        None => {
            let _ = writeln!(
                s,
                "SDM critical depth at {} rpm: none up to 20 × the zero-order minimum depth",
                c.spindle_rpm
            );
        }
    }
    s
}

fn kind_text(kind: BoundaryKind) -> &'static str {
    match kind {
        BoundaryKind::Hopf => "hopf",
        BoundaryKind::Flip => "flip: an odd multiple of half the tooth-passing frequency",
    }
}
