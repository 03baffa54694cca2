//! `vmc-twin bench`: the speed figures (docs/results.md) and how they scale, measured in one
//! command (the criterion benches in `benches/loop.rs` give the same first figures with
//! confidence intervals; this command adds the scaling tables).
//!
//! Wall-clock times of the whole process's work, release build; the figures depend on the
//! machine and its load, so each is the median of `repeats` runs where that is cheap.

use std::time::Instant;

use rayon::prelude::*;

use crate::predict::compiled::{CompiledCompensator, CompiledHybrid};
use crate::predict::controller::{Compensator, Controller};
use crate::predict::predictor::{self, Settings};
use crate::studies::calibration::{self, CampaignConfig, ThermalCycle};
use crate::studies::campaign::ForMachine;
use crate::studies::campaign::{self, EvalError};
use vmc_machine::machine::MachineSpec;
use vmc_machine::program;
use vmc_machine::sim::{self, SampleMode, SimConfig, SimError};
use vmc_machine::twin::Twin;

/// One measured row: what, the figure, its unit.
#[derive(Debug, Clone)]
pub struct Row {
    /// What was measured.
    pub what: String,
    /// The figure.
    pub value: f64,
    /// Its unit.
    pub unit: &'static str,
}

fn row(what: impl Into<String>, value: f64, unit: &'static str) -> Row {
    Row {
        what: what.into(),
        value,
        unit,
    }
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// Compensation query: median ns per query over `repeats` batches of 100,000 queries on one
/// core, for the library's compensator and for the compiled one (the form a servo thread runs,
/// `vmc_predict::compiled`), and the library's batch throughput on all cores (queries/s).
///
/// # Errors
/// Campaign, training or compilation errors.
pub fn query(spec: &MachineSpec, repeats: usize) -> anyhow::Result<Vec<Row>> {
    let data = calibration::calibrate(
        spec,
        &ThermalCycle::calibration_plan(spec),
        &CampaignConfig::new(1),
    )?;
    let settings = campaign::fit_to_data(
        Settings {
            seed: 1,
            ..Settings::for_machine(spec)
        },
        &data,
    );
    let (model, _) = predictor::train_hybrid(&data, &spec.geometry(), &settings)?;
    let names: Vec<String> = spec.sensors.iter().map(|s| s.name.clone()).collect();
    let temps: Vec<f64> = (0..names.len()).map(|i| 22.0 + 0.25 * i as f64).collect();
    const N: usize = 100_000;
    let batch = |comp: &mut dyn Controller, offset: usize| {
        // One set of readings held over the batch, as between two sensor samples.
        comp.on_readings(0.0, &temps);
        let mut acc = 0.0;
        for k in 0..N {
            let s = ((k + offset) % 1000) as f64 * 0.5;
            let q = comp.axis_command_mm([10.0 + s, 60.0 + 0.5 * s, -225.0]);
            acc += q[0];
        }
        std::hint::black_box(acc)
    };
    let median_ns = |comp: &mut dyn Controller| {
        batch(comp, 0); // warm-up
        let per_query_ns: Vec<f64> = (0..repeats.max(1))
            .map(|r| {
                let t = Instant::now();
                batch(comp, r);
                t.elapsed().as_secs_f64() * 1e9 / N as f64
            })
            .collect();
        median(per_query_ns)
    };
    let library_ns = median_ns(&mut Compensator::for_machine(model.clone(), &names)?);
    let compiled = CompiledHybrid::from_predictor(&model)?;
    let instructions = compiled.instruction_set();
    let compiled_ns = median_ns(&mut CompiledCompensator::for_machine(compiled, &names)?);
    let threads = rayon::current_num_threads();
    let t = Instant::now();
    (0..threads * 4).into_par_iter().try_for_each(|r| {
        let mut c = Compensator::for_machine(model.clone(), &names)?;
        batch(&mut c, r);
        Ok::<(), EvalError>(())
    })?;
    let qps = (threads * 4 * N) as f64 / t.elapsed().as_secs_f64();
    Ok(vec![
        row(
            "one compensation query (hybrid: all nets + synthesis + fixed-point solve), one core, median",
            library_ns,
            "ns",
        ),
        row(
            format!("the same query, compiled model (vmc_predict::compiled, {instructions}), one core, median"),
            compiled_ns,
            "ns",
        ),
        row(
            format!("batch compensation throughput, {threads} threads"),
            qps,
            "queries/s",
        ),
    ])
}

/// The 8 h workload: the XY diagonal planned from home, the 9000 rpm heating cycle, the
/// sampling settings at `interp_ms`.
///
/// # Errors
/// Planning errors.
pub fn workload_8h(
    spec: &MachineSpec,
    interp_ms: f64,
) -> Result<(vmc_machine::motion::Plan, ThermalCycle, SimConfig), EvalError> {
    let plan = program::plan_source(
        include_str!("../trajectories/diag_xy.ngc"),
        "diag_xy.ngc",
        spec,
        spec.axes.home_mm,
    )?;
    let cycle = ThermalCycle::calibration_plan(spec)[2].clone();
    let cfg = SimConfig::new(1.0, interp_ms * 1e-3)
        .map_err(SimError::from)?
        .sampling(SampleMode::EveryCycle);
    Ok((plan, cycle, cfg))
}

/// Runs the 8 h workload once on a fresh twin: the cycle's duty, and the diagonal every
/// 30 min with the error at every interpolation sample; returns the number of samples.
///
/// # Errors
/// Simulation errors.
pub fn run_8h(
    spec: &MachineSpec,
    workload: &(vmc_machine::motion::Plan, ThermalCycle, SimConfig),
) -> Result<usize, EvalError> {
    let (plan, cycle, cfg) = workload;
    let mut twin = Twin::new(spec, 1)?;
    let mut n = 0;
    for k in 0..16 {
        calibration::drive(&mut twin, cycle, 0.0, k as f64 * 1800.0, 1.0)?;
        let mut count = sim::CountPoints::default();
        sim::execute(&mut twin, plan, cfg, None, &mut count)?;
        n += count.points;
    }
    Ok(n)
}

/// 8 h of machine time with an XY diagonal every 30 min, motion sampled at `interp_ms`:
/// seconds of wall time (median of `repeats`) and the number of samples.
///
/// # Errors
/// Planning or simulation errors.
pub fn machine_8h(
    spec: &MachineSpec,
    interp_ms: f64,
    repeats: usize,
) -> Result<(f64, usize), EvalError> {
    let workload = workload_8h(spec, interp_ms)?;
    let mut times = Vec::new();
    let mut n = 0;
    for _ in 0..repeats.max(1) {
        let t = Instant::now();
        n = run_8h(spec, &workload)?;
        times.push(t.elapsed().as_secs_f64());
    }
    Ok((median(times), n))
}

/// The default campaign (one seed) calibrated on `cycles`: seconds of wall time and runs.
///
/// # Errors
/// Campaign errors.
pub fn campaign_with(
    spec: &MachineSpec,
    cycles: &[ThermalCycle],
    seeds: &[u64],
) -> Result<(f64, usize), EvalError> {
    let t = Instant::now();
    let (rep, _) =
        campaign::run_campaign_with_cycles(spec, seeds, &Settings::for_machine(spec), cycles, &())?;
    Ok((t.elapsed().as_secs_f64(), rep.runs.len()))
}

/// The typical calibration cycles, `n` of them: the first `n` of the set, repeated (as the same
/// duty on another day, renamed `<name>_day<k>`) when `n` exceeds it.
pub fn calibration_cycles(spec: &MachineSpec, n: usize) -> Vec<ThermalCycle> {
    let base = ThermalCycle::calibration_plan(spec);
    (0..n)
        .map(|i| {
            let mut c = base[i % base.len()].clone();
            if i >= base.len() {
                c.name = format!("{}_day{}", c.name, i / base.len() + 1);
            }
            c
        })
        .collect()
}

/// A CAM-like finishing program of at least `min_bytes`: zig-zag rows over a wavy surface in
/// the reference machine's vise stock (part zero on its top; X 0…100, Y 0…80 mm), one `G1` with
/// X, Y and Z per 0.5 mm, words only every milling post emits. Returns the text and its lines.
#[must_use]
pub fn finishing_program(min_bytes: usize) -> (String, usize) {
    use std::fmt::Write as _;
    let mut text = String::from(
        "(SURFACE FINISHING, BALL END MILL: GENERATED BY VMC-TWIN BENCH)\n\
         G90 G94 G17 G21\nG10 L2 P1 X230. Y160. Z-250.\nG54\nS8000 M3\nG0 X0. Y0. Z5.\n",
    );
    let mut lines = 6;
    let (mut row, step_mm, row_step_mm) = (0usize, 0.5, 0.4);
    while text.len() < min_bytes {
        let y = (row as f64 * row_step_mm) % 80.0;
        let n = (100.0 / step_mm) as usize;
        for k in 0..=n {
            let i = if row % 2 == 0 { k } else { n - k };
            let x = i as f64 * step_mm;
            let z = -2.0 + 1.5 * (x / 15.0).sin() * (y / 12.0).cos();
            let feed = if k == 0 { " F2000." } else { "" };
            // Writing to a String cannot fail.
            let _ = writeln!(text, "G1 X{x:.3} Y{y:.3} Z{z:.4}{feed}");
            lines += 1;
        }
        row += 1;
    }
    text.push_str("G0 Z5.\nM5\nM30\n");
    (text, lines + 3)
}

/// Interpreting and planning [`finishing_program`] of 1 MB: the median wall time (s) of the
/// interpreter alone and of interpreter + planner over `repeats` runs, and, when LinuxCNC's
/// `rs274` is on the PATH, its time on the same file in the same run (`None` otherwise).
///
/// # Errors
/// The program refused (a defect), the temporary file for `rs274` not writable.
pub fn gcode_1mb(spec: &MachineSpec, repeats: usize) -> anyhow::Result<GcodeTimes> {
    let (text, lines) = finishing_program(1 << 20);
    let cfg = vmc_gcode::interp::InterpConfig::default();
    let mut interp_s = Vec::new();
    let mut plan_s = Vec::new();
    for _ in 0..repeats.max(1) {
        let t0 = Instant::now();
        std::hint::black_box(vmc_gcode::interp::run_program(&text, &cfg)?);
        interp_s.push(t0.elapsed().as_secs_f64());
        let t0 = Instant::now();
        let plan = program::plan_source_unchecked(&text, "finishing.ngc", spec, spec.axes.home_mm)?;
        plan_s.push(t0.elapsed().as_secs_f64());
        std::hint::black_box(plan);
    }
    let rs274_s = time_rs274(&text)?;
    Ok(GcodeTimes {
        bytes: text.len(),
        lines,
        interpret_s: median(interp_s),
        interpret_and_plan_s: median(plan_s),
        rs274_s,
    })
}

/// Timings of [`gcode_1mb`].
#[derive(Debug, Clone, Copy)]
pub struct GcodeTimes {
    /// Program size, bytes.
    pub bytes: usize,
    /// Program lines.
    pub lines: usize,
    /// Our interpreter alone, s.
    pub interpret_s: f64,
    /// Interpreter and motion planner, s.
    pub interpret_and_plan_s: f64,
    /// `rs274 -g` on the same file (output discarded), s; `None` when it is not installed.
    pub rs274_s: Option<f64>,
}

/// Wall time of `rs274 -g` on `text` (written to a private temporary folder, which is also its
/// HOME: it keeps a tool-table file there); `None` when `rs274` cannot be started.
fn time_rs274(text: &str) -> anyhow::Result<Option<f64>> {
    use std::process::{Command, Stdio};
    let dir = std::env::temp_dir().join(format!("vmc-twin-bench-{}", std::process::id()));
    std::fs::create_dir_all(&dir)?;
    let file = dir.join("finishing.ngc");
    std::fs::write(&file, text)?;
    let t0 = Instant::now();
    let status = Command::new("rs274")
        .arg("-g")
        .arg(&file)
        .env("HOME", &dir)
        .current_dir(&dir)
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status();
    let elapsed = t0.elapsed().as_secs_f64();
    std::fs::remove_dir_all(&dir).ok();
    Ok(status.ok().filter(|s| s.success()).map(|_| elapsed))
}

/// Peak resident memory of this process so far (VmHWM), MiB; None where /proc is missing.
pub fn peak_rss_mib() -> Option<f64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kib: f64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib / 1024.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_finishing_program_is_a_megabyte_of_moves_inside_the_travel() {
        let spec = MachineSpec::reference();
        let (text, lines) = finishing_program(1 << 20);
        assert!(text.len() >= 1 << 20);
        assert_eq!(lines, text.lines().count());
        assert!(lines > 35_000, "{lines}");
        let plan = program::plan_source(&text, "f.ngc", &spec, spec.axes.home_mm).unwrap();
        assert!(plan.segments().len() > 35_000);
    }

    #[test]
    fn more_calibration_cycles_than_the_set_repeat_it_under_new_names() {
        let spec = MachineSpec::reference();
        let m = ThermalCycle::calibration_plan(&spec).len();
        let c = calibration_cycles(&spec, 2 * m + 1);
        assert_eq!(c.len(), 2 * m + 1);
        let names: std::collections::HashSet<_> = c.iter().map(|c| c.name.clone()).collect();
        assert_eq!(
            names.len(),
            c.len(),
            "names must stay unique (validation split by cycle)"
        );
        assert_eq!(c[m].phases, c[0].phases);
        assert!(c[2 * m].name.ends_with("_day3"), "{}", c[2 * m].name);
    }
}
