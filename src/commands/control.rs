//! `vmc-twin control design`, `lobes --controller` and `cut --controller`: active chatter
//! control of the piezo-actuated blade — design an LQG or H∞ controller (strategy 1 on the
//! structure, strategy 2 on the structure coupled to the cut), its figures, and what it buys
//! in stability lobes and in a time-domain cut with saturation.

use std::fmt::Write as _;
use std::io::Write;
use std::path::PathBuf;

use anyhow::{bail, Context, Result};
use serde::{Deserialize, Serialize};

use super::lobes::{LobesOutputs, ShardOutput};
use crate::dynamics::control::blade::BladePlant;
use crate::dynamics::control::closed_loop::{
    attenuation, close, lobes_block as closed_lobes_block, open, sampled_model, ClosedLoop,
};
use crate::dynamics::control::design::{to_metres, CuttingCoupling, DesignPlant};
use crate::dynamics::control::robust::{check_sampling, SampledController};
use crate::dynamics::control::simulate::{
    simulate, ControlledCut, ControlledCutOptions, LoopElement,
};
use crate::dynamics::control::StateSpace;
use crate::dynamics::cut::Verdict;
use crate::dynamics::{LobePoint, Resolution, StepRule};
use crate::files;
use vmc_machine::blade::{
    ControllerFile, Figures, ModeFigure, Plant, ACTING_DB, CONTROLLER_FORMAT,
    SAMPLES_PER_ACTED_PERIOD,
};

/// Controller type.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    /// LQR + Kalman filter.
    Lqg,
    /// Glover–Doyle H∞.
    Hinf,
    /// H∞ with a weighted input-multiplicative uncertainty and a second-order roll-off.
    RobustHinf,
}

/// What to design, validated.
pub struct DesignConfig {
    /// The plant file's contents.
    pub plant: Plant,
    /// Where it came from.
    pub plant_source: String,
    /// LQG or H∞.
    pub kind: Kind,
    /// 1 or 2.
    pub strategy: u8,
    /// Overrides the file's low-pass corner of the chosen controller, Hz (`Some(None)`: none).
    pub lowpass_hz: Option<Option<f64>>,
    /// The controller file to write.
    pub out: Option<PathBuf>,
    /// Overwrite it.
    pub force: bool,
    /// Judge the design on perturbed blades (`--robustness`) over these lobes.
    pub robustness: Option<super::control_robust::SweepConfig>,
}

/// The name of a controller type in files and reports.
pub fn kind_name(k: Kind) -> &'static str {
    match k {
        Kind::Lqg => "lqg",
        Kind::Hinf => "hinf",
        Kind::RobustHinf => "robust-hinf",
    }
}

/// Designs the controller on the plant; returns it (y in m → u in V) and γ for H∞.
pub fn design_controller(cfg: &DesignConfig, bp: &BladePlant) -> Result<(StateSpace, Option<f64>)> {
    let p = &cfg.plant;
    let base = match cfg.strategy {
        1 => DesignPlant::structure(bp),
        2 => {
            let Some(s2) = p.strategy2 else {
                bail!(
                    "{}: strategy 2 needs a [strategy2] table (design_depth_mm, pade_order)",
                    cfg.plant_source
                );
            };
            DesignPlant::coupled(
                bp,
                &CuttingCoupling {
                    tool: p.tool,
                    immersion: p.immersion,
                    milling: p.milling,
                    depth_mm: s2.design_depth_mm,
                    spindle_rpm: s2.design_rpm.unwrap_or(p.spindle_rpm),
                    pade_order: s2.pade_order,
                },
            )?
        }
        s => bail!("--strategy must be 1 or 2, got {s}"),
    };
    let dp = base.sampled(p.sample_rate_hz)?;
    Ok(match cfg.kind {
        Kind::Lqg => {
            let mut w = p.lqg;
            if let Some(lp) = cfg.lowpass_hz {
                w.lowpass_hz = lp;
            }
            (to_metres(&dp.lqg(&w)?), None)
        }
        Kind::Hinf => {
            let mut w = p.hinf;
            if let Some(lp) = cfg.lowpass_hz {
                w.lowpass_hz = lp;
            }
            let (k, g) = dp.hinf(&w)?;
            (to_metres(&k), Some(g))
        }
        Kind::RobustHinf => {
            let (k, g) = dp.robust_hinf(&p.hinf, &p.robust_hinf)?;
            (to_metres(&k), Some(g))
        }
    })
}

/// The figures of a controller on its blade.
pub fn figures(p: &Plant, bp: &BladePlant, k: &StateSpace) -> Result<(Figures, ClosedLoop)> {
    let closed = close(bp, &sampled_model(k, p.sample_rate_hz)?)?;
    let element = LoopElement::new(k, p.sample_rate_hz, p.blade.actuator.max_voltage_v)?;
    let f = bp.frequencies_hz();
    let (effort, effort_hz) = closed.effort_peak(f[0] / 3.0, 3.0 * f[f.len() - 1]);
    let mut poles: Vec<[f64; 2]> = closed.poles().iter().map(|l| [l.re, l.im]).collect();
    poles.sort_by(|a, b| (a[0].hypot(a[1])).total_cmp(&b[0].hypot(b[1])));
    let modes = attenuation(bp, &closed)
        .iter()
        .map(|m| ModeFigure {
            frequency_hz: m.frequency_hz,
            open_peak_m_per_n: m.open_peak_m_per_n,
            closed_peak_m_per_n: m.closed_peak_m_per_n,
            attenuation_db: m.attenuation_db,
        })
        .collect();
    Ok((
        Figures {
            poles_rad_per_s: poles,
            modes,
            effort_peak_v_per_n: effort,
            effort_peak_hz: effort_hz,
            sampled_loop_spectral_radius: element.loop_spectral_radius(bp),
        },
        closed,
    ))
}

/// Designs the controller, prints its figures and writes the controller file.
///
/// # Errors
/// No stabilising design, an unstable closed or sampled loop, an output that may not be
/// written.
pub fn design(cfg: &DesignConfig, out: &mut dyn Write) -> Result<()> {
    if let Some(path) = &cfg.out {
        files::check_writable(path, cfg.force)?;
    }
    let p = &cfg.plant;
    let bp = p.blade.plant()?;
    // A chatter controller acts on the first mode at least: a sampling that cannot see it is
    // refused before any design (whose model of the sampling lag would be meaningless).
    let first = [(bp.frequencies_hz()[0], 0.0)];
    check_sampling(
        &first,
        p.sample_rate_hz,
        ACTING_DB,
        SAMPLES_PER_ACTED_PERIOD / 2.0,
    )
    .map_err(|e| anyhow::anyhow!("{}: {e}", cfg.plant_source))?;
    let (k, gamma) = design_controller(cfg, &bp).with_context(|| cfg.plant_source.to_string())?;
    let (fig, closed) = figures(p, &bp, &k)?;
    let mut text = String::new();
    writeln!(
        text,
        "vmc-twin control design: {} (strategy {}) on {} ({})",
        kind_name(cfg.kind),
        cfg.strategy,
        p.name,
        cfg.plant_source
    )?;
    let freqs: Vec<String> = bp
        .frequencies_hz()
        .iter()
        .map(|f| format!("{f:.1}"))
        .collect();
    writeln!(
        text,
        "blade: {} modes, stack held: {} Hz; tip stiffness {:.1} N/mm (model), {:.1} N/mm (exact beam), free cantilever {:.1} N/mm",
        bp.modes(),
        freqs.join(", "),
        bp.static_tip_stiffness_n_per_mm(),
        p.blade.propped_tip_stiffness_n_per_mm(),
        p.blade.cantilever_tip_stiffness_n_per_mm()
    )?;
    if let Some(g) = gamma {
        writeln!(
            text,
            "gamma {g:.4} (bisection, 5 % above the smallest feasible)"
        )?;
    }
    writeln!(
        text,
        "controller: {} states, sampled at {:.0} Hz with a one-sample delay; sampled-loop spectral radius {:.5}",
        k.states(),
        p.sample_rate_hz,
        fig.sampled_loop_spectral_radius
    )?;
    if !closed.is_stable() || fig.sampled_loop_spectral_radius >= 1.0 {
        out.write_all(text.as_bytes())?;
        bail!("the closed loop is unstable: change the weights (more effort weight, a low-pass filter)");
    }
    let modes: Vec<(f64, f64)> = fig
        .modes
        .iter()
        .map(|m| (m.frequency_hz, m.attenuation_db))
        .collect();
    if let Err(e) = check_sampling(
        &modes,
        p.sample_rate_hz,
        ACTING_DB,
        SAMPLES_PER_ACTED_PERIOD / 2.0,
    ) {
        out.write_all(text.as_bytes())?;
        bail!("{}: {e}", cfg.plant_source);
    }
    writeln!(
        text,
        "attenuation of each mode (peak |tip/F| open vs closed loop):"
    )?;
    for (i, m) in fig.modes.iter().enumerate() {
        writeln!(
            text,
            "  mode {} {:>8.1} Hz  open {:.3e} m/N  closed {:.3e} m/N  {:>6.1} dB",
            i + 1,
            m.frequency_hz,
            m.open_peak_m_per_n,
            m.closed_peak_m_per_n,
            m.attenuation_db
        )?;
    }
    let ac = &p.blade.actuator;
    writeln!(
        text,
        "actuator effort: peak |u/F| {:.3} V/N at {:.1} Hz ({:.3} µm of stroke per N); {:.0} V saturation at {:.1} N",
        fig.effort_peak_v_per_n,
        fig.effort_peak_hz,
        fig.effort_peak_v_per_n * ac.gain_m_per_v() * 1e6,
        ac.max_voltage_v,
        ac.max_voltage_v / fig.effort_peak_v_per_n
    )?;
    writeln!(
        text,
        "closed-loop poles (rad/s, slowest first; continuous model with the sampling delay):"
    )?;
    for pole in fig.poles_rad_per_s.iter().filter(|l| l[1] >= 0.0).take(8) {
        let wn = pole[0].hypot(pole[1]);
        writeln!(
            text,
            "  {:>12.1} {:+12.1}i   {:>8.1} Hz  zeta {:.4}",
            pole[0],
            pole[1],
            wn / (2.0 * std::f64::consts::PI),
            -pole[0] / wn
        )?;
    }
    out.write_all(text.as_bytes())?;
    if let Some(path) = &cfg.out {
        let file = ControllerFile {
            format: CONTROLLER_FORMAT.to_string(),
            kind: kind_name(cfg.kind).to_string(),
            strategy: cfg.strategy,
            gamma,
            plant: p.clone(),
            controller: ControllerFile::matrices(&k),
            figures: fig,
        };
        let json = serde_json::to_string_pretty(&file)?;
        files::write_atomic(path, json.as_bytes(), cfg.force)?;
        writeln!(out, "wrote {}", path.display())?;
    }
    if let Some(sweep) = &cfg.robustness {
        let c = SampledController {
            k: &k,
            sample_rate_hz: p.sample_rate_hz,
            max_voltage_v: p.blade.actuator.max_voltage_v,
        };
        super::control_robust::sweep(p, &c, sweep, out)?;
    }
    Ok(())
}

/// The structure a controller is judged on: the controller file's own plant, or another
/// plant file's (`--plant FILE`), whose blade, cutter and cut replace the stored ones (the
/// sampling stays the controller's).
#[derive(Debug, Clone)]
pub struct JudgedOn {
    /// The plant (blade, cutter, cut).
    pub plant: Plant,
    /// Where it came from (`None`: the controller file's own).
    pub source: Option<String>,
}

impl JudgedOn {
    /// The controller file's own plant.
    pub fn own(file: &ControllerFile) -> Self {
        Self {
            plant: file.plant.clone(),
            source: None,
        }
    }

    /// A line for the report when the plant is another file's.
    pub fn report_line(&self, file: &ControllerFile) -> Option<String> {
        let src = self.source.as_ref()?;
        let f = |p: &Plant| {
            p.blade.plant().map_or_else(
                |_| String::from("?"),
                |bp| {
                    bp.frequencies_hz()
                        .iter()
                        .map(|f| format!("{f:.1}"))
                        .collect::<Vec<_>>()
                        .join(", ")
                },
            )
        };
        Some(format!(
            "judged on {} ({src}): stack-held modes {} Hz; designed on {}: {} Hz",
            self.plant.name,
            f(&self.plant),
            file.plant.name,
            f(&file.plant)
        ))
    }
}

/// Lobes with a controller, validated.
pub struct ControlLobesConfig {
    /// The controller file.
    pub file: ControllerFile,
    /// Where it came from.
    pub source: String,
    /// The structure it is judged on.
    pub judged: JudgedOn,
    /// Spindle speeds, rpm.
    pub speeds_rpm: Vec<f64>,
    /// Resolution of the semi-discretisation (`--steps N`: [`Resolution::Fixed`]; default
    /// [`blade_resolution`]).
    pub resolution: Resolution,
    /// CSV output (with `shard`: its file name names the CSV the merge writes).
    pub out: Option<PathBuf>,
    /// A Rerun recording of the open- and closed-loop lobes.
    pub rrd: Option<PathBuf>,
    /// Overwrite them.
    pub force: bool,
    /// Compute only this shard of the speeds and write it for `merge`.
    pub shard: Option<ShardOutput>,
}

/// What the report, the CSV and the recording of `lobes --controller` say besides the points.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ControlLobesHead {
    /// The plant's name.
    pub plant_name: String,
    /// The controller type as the file names it (`lqg`, `hinf`).
    pub kind: String,
    /// The design strategy, 1 or 2.
    pub strategy: u8,
    /// Where the controller file came from.
    pub source: String,
    /// The plant file it is judged on, when not its own (`--plant`).
    #[serde(default)]
    pub judged_on: Option<String>,
    /// The semi-discretisation's steps per tooth period when fixed by `--steps`; `None`: chosen
    /// per speed by the converged rule of [`blade_resolution`].
    pub steps_per_period: Option<usize>,
    /// Every spindle speed asked for, rpm, in order.
    pub speeds_rpm: Vec<f64>,
}

impl ControlLobesHead {
    /// The head of `cfg`.
    pub fn of(cfg: &ControlLobesConfig) -> Self {
        Self {
            plant_name: cfg.file.plant.name.clone(),
            kind: cfg.file.kind.clone(),
            strategy: cfg.file.strategy,
            source: cfg.source.clone(),
            judged_on: cfg.judged.report_line(&cfg.file),
            steps_per_period: match cfg.resolution {
                Resolution::Fixed(m) => Some(m),
                Resolution::Converged(_) => None,
            },
            speeds_rpm: cfg.speeds_rpm.clone(),
        }
    }
}

/// Most steps per tooth period of the blade's converged lobes. The blade's 8 kHz mode asks
/// the default rule for its cap (2560 steps) at low speed, minutes for 200 speeds; capped at
/// 640 (320 and 640 extrapolated) the closed-loop depths stay within 0.12 % of the uncapped
/// rule in a quarter of the time, where a fixed 160 steps are up to 10 % deep (see the decision
/// record on converged lobes).
pub const BLADE_MAX_STEPS: usize = 640;

/// The default resolution of the blade's lobes: the converged rule capped at
/// [`BLADE_MAX_STEPS`].
pub fn blade_resolution() -> Resolution {
    Resolution::Converged(StepRule {
        max_steps: BLADE_MAX_STEPS,
        ..StepRule::default()
    })
}

/// Deepest depth searched by the lobes, mm.
const MAX_DEPTH_MM: f64 = 50.0;
/// Depth tolerance of the lobes, mm.
const DEPTH_TOL_MM: f64 = 1e-4;

fn minimum(points: &[LobePoint]) -> Option<&LobePoint> {
    points
        .iter()
        .min_by(|a, b| a.critical_depth_mm.total_cmp(&b.critical_depth_mm))
}

/// Open- and closed-loop lobes of the blade; prints both minima and the table, writes the CSV
/// (a shard of the speeds: [`super::lobes_shard::control_lobes_shard`]).
///
/// # Errors
/// An unstable loop, an output that may not be written.
pub fn lobes(cfg: &ControlLobesConfig, out: &mut dyn Write) -> Result<()> {
    let outputs = LobesOutputs {
        csv: cfg.out.as_deref(),
        rrd: cfg.rrd.as_deref(),
        force: cfg.force,
    };
    super::lobes::check_outputs(&outputs)?;
    let [ol, cl] = lobes_block(cfg, 0..cfg.speeds_rpm.len())?
        .map(|curve| curve.into_iter().flatten().collect::<Vec<_>>());
    write_lobes(&ControlLobesHead::of(cfg), ol, cl, &outputs, out)
}

/// The open- and closed-loop lobe points of the block `block` of the speeds, one per speed
/// (`None` without a boundary below 50 mm): the same bits as the whole list's.
///
/// # Errors
/// An unstable loop, a bad plant or controller.
pub fn lobes_block(
    cfg: &ControlLobesConfig,
    block: std::ops::Range<usize>,
) -> Result<[Vec<Option<LobePoint>>; 2]> {
    let p = &cfg.judged.plant;
    let bp = p.blade.plant()?;
    let k = cfg.file.state_space()?;
    let closed = close(&bp, &sampled_model(&k, cfg.file.plant.sample_rate_hz)?)?;
    if !closed.is_stable() {
        bail!(
            "the {} controller of {} makes the loop of {} unstable without cutting: no lobes",
            cfg.file.kind,
            cfg.source,
            cfg.judged.source.as_deref().unwrap_or("its plant")
        );
    }
    let cut = super::control_robust::lobe_cut(p);
    let tol = (MAX_DEPTH_MM, DEPTH_TOL_MM);
    let (speeds, res) = (&cfg.speeds_rpm, cfg.resolution);
    let ol = closed_lobes_block(&bp, &open(&bp), &cut, speeds, block.clone(), tol, res)?;
    let cl = closed_lobes_block(&bp, &closed, &cut, speeds, block, tol, res)?;
    Ok([ol, cl])
}

/// Prints the report of the open- (`ol`) and closed-loop (`cl`) lobes (both minima, their
/// ratio and the table), writes the CSV and the recording.
///
/// # Errors
/// A file that cannot be written.
pub fn write_lobes(
    head: &ControlLobesHead,
    ol: Vec<LobePoint>,
    cl: Vec<LobePoint>,
    outputs: &LobesOutputs<'_>,
    out: &mut dyn Write,
) -> Result<()> {
    let mut text = String::new();
    writeln!(
        text,
        "vmc-twin lobes: {} with the {} controller (strategy {}) of {}, {} speeds, closed-loop semi-discretisation",
        head.plant_name,
        head.kind,
        head.strategy,
        head.source,
        head.speeds_rpm.len(),
    )?;
    let resolution = match head.steps_per_period {
        Some(m) => {
            format!("{m} steps per tooth period at every speed (fixed by --steps, not checked)")
        }
        None => match blade_resolution() {
            Resolution::Converged(rule) => super::lobes::converged_text(&rule),
            Resolution::Fixed(m) => format!("{m} steps per tooth period"),
        },
    };
    writeln!(text, "resolution: {resolution}")?;
    if let Some(line) = &head.judged_on {
        writeln!(text, "{line}")?;
    }
    let (mo, mc) = (minimum(&ol), minimum(&cl));
    for (label, m) in [("open loop  ", mo), ("closed loop", mc)] {
        match m {
            Some(m) => writeln!(
                text,
                "{label}: minimum critical depth {:.4} mm at {:.0} rpm (chatter at {:.1} Hz)",
                m.critical_depth_mm, m.spindle_rpm, m.chatter_frequency_hz
            )?,
            None => writeln!(text, "{label}: no boundary below {MAX_DEPTH_MM} mm")?,
        }
    }
    if let (Some(a), Some(b)) = (mo, mc) {
        writeln!(
            text,
            "the controller multiplies the minimum critical depth by {:.2} (linear loop, no saturation: confirm with `cut --controller`)",
            b.critical_depth_mm / a.critical_depth_mm
        )?;
    }
    let at = |pts: &[LobePoint], n: f64| pts.iter().find(|l| l.spindle_rpm == n).copied();
    let mut csv = String::from(
        "spindle_rpm,open_depth_mm,closed_depth_mm,open_steps_per_period,closed_steps_per_period\n",
    );
    let depth =
        |p: Option<LobePoint>| p.map_or(String::new(), |p| format!("{:.6}", p.critical_depth_mm));
    let steps = |p: Option<LobePoint>| {
        p.and_then(|p| p.steps_per_period)
            .map_or(String::new(), |m| m.to_string())
    };
    writeln!(
        text,
        "  {:>12} {:>16} {:>16} {:>11} {:>13}",
        "spindle_rpm", "open_depth_mm", "closed_depth_mm", "open_steps", "closed_steps"
    )?;
    let every = head.speeds_rpm.len().div_ceil(41).max(1);
    for (i, &n) in head.speeds_rpm.iter().enumerate() {
        let (o, c) = (at(&ol, n), at(&cl, n));
        let (od, cd, os, cs) = (depth(o), depth(c), steps(o), steps(c));
        writeln!(csv, "{n},{od},{cd},{os},{cs}")?;
        if i % every == 0 {
            writeln!(text, "  {n:>12.0} {od:>16} {cd:>16} {os:>11} {cs:>13}")?;
        }
    }
    out.write_all(text.as_bytes())?;
    if let Some(path) = outputs.csv {
        files::write_atomic(path, csv.as_bytes(), outputs.force)?;
        writeln!(out, "wrote {}", path.display())?;
    }
    if let Some(path) = outputs.rrd {
        use crate::record::chatter::{record_lobe_diagram, LobeCurve};
        let curves = [
            LobeCurve {
                name: "open loop".into(),
                points: ol,
            },
            LobeCurve {
                name: format!("with {} (strategy {})", head.kind, head.strategy),
                points: cl,
            },
        ];
        let md = format!(
            "# vmc-twin lobes --controller\n\nThe blade's stability lobes without and with the \
             controller (closed-loop semi-discretisation, linear loop: no saturation).\n\n\
             ```text\n{text}```\n"
        );
        let title = format!("vmc-twin lobes --controller {}", head.source);
        let bytes = record_lobe_diagram(path, outputs.force, &title, &curves, &[], &md)?;
        super::wrote_recording(out, path, bytes, "")?;
    }
    Ok(())
}

/// A cut of the blade with a controller, validated.
pub struct ControlCutConfig {
    /// The controller file.
    pub file: ControllerFile,
    /// Where it came from.
    pub source: String,
    /// The structure it is judged on.
    pub judged: JudgedOn,
    /// Spindle speed, rpm.
    pub spindle_rpm: f64,
    /// Axial depth, mm.
    pub depth_mm: f64,
    /// Feed per tooth, mm.
    pub feed_per_tooth_mm: f64,
    /// Horizon in tooth periods.
    pub tooth_periods: usize,
    /// CSV output.
    pub out: Option<PathBuf>,
    /// Overwrite it.
    pub force: bool,
}

fn verdict_name(v: Verdict) -> &'static str {
    match v {
        Verdict::Stable => "stable",
        Verdict::Chatter => "chatter",
    }
}

/// Simulates the cut without and with the controller (sampled, saturated) and reports both.
///
/// # Errors
/// Values the dynamics refuses, an output that may not be written.
pub fn cut(cfg: &ControlCutConfig, out: &mut dyn Write) -> Result<()> {
    if let Some(path) = &cfg.out {
        files::check_writable(path, cfg.force)?;
    }
    let p = &cfg.judged.plant;
    let rate_hz = cfg.file.plant.sample_rate_hz;
    let bp = p.blade.plant()?;
    let k = cfg.file.state_space()?;
    let ac = &p.blade.actuator;
    let element = LoopElement::new(&k, rate_hz, ac.max_voltage_v)?;
    let options = ControlledCutOptions {
        sample_period_s: 1.0 / rate_hz,
        tooth_periods: cfg.tooth_periods,
        ..ControlledCutOptions::default()
    };
    let cut = super::control_robust::lobe_cut(p);
    let run = |c: Option<&LoopElement>| {
        simulate(
            &bp,
            c,
            &cut,
            cfg.spindle_rpm,
            cfg.depth_mm,
            cfg.feed_per_tooth_mm,
            &options,
        )
    };
    let (ol, cl) = (run(None)?, run(Some(&element))?);
    let mut text = String::new();
    writeln!(
        text,
        "vmc-twin cut: {} at {} rpm, a_p {} mm, f_z {} mm, a_e/D {:.4}, {} tooth periods, {} controller (strategy {}) of {} sampled at {:.0} Hz",
        p.name,
        cfg.spindle_rpm,
        cfg.depth_mm,
        cfg.feed_per_tooth_mm,
        p.immersion,
        cfg.tooth_periods,
        cfg.file.kind,
        cfg.file.strategy,
        cfg.source,
        rate_hz
    )?;
    if let Some(line) = cfg.judged.report_line(&cfg.file) {
        writeln!(text, "{line}")?;
    }
    let half = |r: &ControlledCut| {
        let n = r.tip_m.len();
        r.tip_m[n / 2..].iter().fold(0.0f64, |m, v| m.max(v.abs())) * 1e6
    };
    for (label, r) in [("open loop  ", &ol), ("closed loop", &cl)] {
        if r.growth_ratio.is_infinite() {
            writeln!(
                text,
                "{label}: chatter  (the vibration grew past 1 m: the linear force law has no loss of contact to bound it)"
            )?;
        } else {
            writeln!(
                text,
                "{label}: {}  (growth ratio {:.3}), largest tip vibration over the last half {:.2} µm",
                verdict_name(r.verdict),
                r.growth_ratio,
                half(r)
            )?;
        }
    }
    writeln!(
        text,
        "actuator: largest command {:.1} V of ±{:.0} V ({:.2} µm of the {:.0} µm stroke), over the last half {:.1} V, saturated {:.1} % of the samples",
        cl.max_command_v,
        ac.max_voltage_v,
        cl.max_command_v * ac.gain_m_per_v() * 1e6,
        ac.stroke_um,
        cl.max_command_last_half_v,
        100.0 * cl.saturated_fraction
    )?;
    out.write_all(text.as_bytes())?;
    if let Some(path) = &cfg.out {
        let mut csv = String::from("time_s,tip_open_um,tip_closed_um,command_v,force_closed_n\n");
        let n = ol.tip_m.len().min(cl.tip_m.len());
        for i in 0..n {
            writeln!(
                csv,
                "{:.8},{:.6},{:.6},{:.4},{:.4}",
                i as f64 * cl.sample_period_s,
                ol.tip_m[i] * 1e6,
                cl.tip_m[i] * 1e6,
                cl.command_v[i],
                cl.force_n[i]
            )?;
        }
        files::write_atomic(path, csv.as_bytes(), cfg.force)?;
        writeln!(out, "wrote {}", path.display())?;
    }
    Ok(())
}
