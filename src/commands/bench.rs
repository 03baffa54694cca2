//! `vmc-twin bench`: the speed figures (compensation query, 8 h of machine time, campaign) and
//! how they scale.

use std::io::Write;

use anyhow::Result;

use crate::benchmark;
use crate::studies::calibration::ThermalCycle;
use vmc_machine::machine::MachineSpec;

/// What to measure, validated.
pub struct BenchConfig {
    /// Repeats of the cheap measurements (≥ 1; the median is reported).
    pub repeats: usize,
    /// Skip the campaign scaling.
    pub quick: bool,
}

/// Median wall time (s) over `repeats` of interpreting the 1 MB program of
/// [`benchmark::finishing_program`] and writing its canonical calls as `vmc-twin interpret`
/// does, to a sink: the work `rs274 -g` does on the same file.
///
/// # Errors
/// The program refused (a defect).
fn interpret_and_write_s(repeats: usize) -> Result<f64> {
    let (text, _) = benchmark::finishing_program(1 << 20);
    let cfg = vmc_gcode::interp::InterpConfig::default();
    let mut times = Vec::new();
    for _ in 0..repeats.max(1) {
        let t0 = std::time::Instant::now();
        let moves = vmc_gcode::interp::run_program(&text, &cfg)?;
        super::interpret::write_calls(&moves, &mut std::io::sink())?;
        times.push(t0.elapsed().as_secs_f64());
    }
    times.sort_by(f64::total_cmp);
    Ok(times[times.len() / 2])
}

/// Measures and prints the figures.
///
/// # Errors
/// Simulation errors, the writer's.
pub fn bench(cfg: &BenchConfig, out: &mut dyn Write) -> Result<()> {
    let spec = MachineSpec::reference();
    writeln!(
        out,
        "vmc-twin bench on {} ({} threads; release build: {})",
        spec.machine.name,
        rayon::current_num_threads(),
        !cfg!(debug_assertions)
    )?;
    for r in benchmark::query(&spec, cfg.repeats)? {
        writeln!(out, "  {:<90} {:>12.1} {}", r.what, r.value, r.unit)?;
    }
    writeln!(
        out,
        "8 h of machine time, XY diagonal every 30 min, error at every interpolation sample:"
    )?;
    writeln!(
        out,
        "  {:>10} {:>12} {:>10} {:>14}",
        "cycle ms", "samples", "wall s", "ns / sample"
    )?;
    for ms in [4.0, 2.0, 1.0, 0.5, 0.25] {
        let (s, n) = benchmark::machine_8h(&spec, ms, cfg.repeats.min(3))?;
        writeln!(
            out,
            "  {ms:>10} {n:>12} {s:>10.3} {:>14.0}",
            s * 1e9 / n.max(1) as f64
        )?;
    }
    let g = benchmark::gcode_1mb(&spec, cfg.repeats.min(5))?;
    writeln!(
        out,
        "G-code: a CAM-like finishing program of {:.2} MB ({} lines):",
        g.bytes as f64 / 1e6,
        g.lines
    )?;
    writeln!(out, "  {:<90} {:>12.3} s", "interpret", g.interpret_s)?;
    writeln!(
        out,
        "  {:<90} {:>12.3} s",
        "interpret and write the canonical calls (as `vmc-twin interpret`, output discarded)",
        interpret_and_write_s(cfg.repeats.min(5))?
    )?;
    writeln!(
        out,
        "  {:<90} {:>12.3} s",
        "interpret + plan", g.interpret_and_plan_s
    )?;
    match g.rs274_s {
        Some(s) => writeln!(
            out,
            "  {:<90} {:>12.3} s",
            "LinuxCNC rs274 -g on the same file (process, output discarded)", s
        )?,
        None => writeln!(out, "  LinuxCNC rs274: not installed, not compared")?,
    }
    if !cfg.quick {
        writeln!(
            out,
            "campaign (seed 1: calibration, 3 trainings, 147 held-out runs) vs calibration cycles:"
        )?;
        writeln!(out, "  {:>8} {:>8} {:>10}", "cycles", "runs", "wall s")?;
        let m = ThermalCycle::calibration_plan(&spec).len();
        for n in [2, 4, m, 2 * m] {
            let (s, runs) =
                benchmark::campaign_with(&spec, &benchmark::calibration_cycles(&spec, n), &[1])?;
            writeln!(out, "  {n:>8} {runs:>8} {s:>10.2}")?;
        }
        let (s, runs) =
            benchmark::campaign_with(&spec, &ThermalCycle::calibration_plan(&spec), &[1, 2, 3])?;
        writeln!(out, "default campaign, seeds 1,2,3 ({runs} runs): {s:.2} s")?;
    }
    if let Some(m) = benchmark::peak_rss_mib() {
        writeln!(out, "peak resident memory of this process: {m:.0} MiB")?;
    }
    Ok(())
}
