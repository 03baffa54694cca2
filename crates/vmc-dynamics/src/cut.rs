//! One cut in the time domain: the vibration of the tool tip and the cutting forces of a cut
//! (speed, axial depth, radial immersion, feed per tooth, up or down milling), its spectrum and
//! a stable/chatter verdict.
//!
//! Model: the process force of [`crate::time_domain`] (static chip f_z sinφ plus the
//! regenerative term, edge forces, process damping, a tooth that leaves the material cuts
//! nothing, helical disks) integrated by RK4 with m steps per tooth period.
//!
//! Start: the simulation starts in the steady cut — the tooth-periodic forced vibration that a
//! long stable cut settles to, computed exactly for the discretised structure (see
//! [`SteadyCut`]) — with every modal displacement disturbed by `disturbance_m` (default
//! 0.1 µm). The entry into the material is not simulated: the horizon is spent on the question
//! whether a disturbance of the steady cut dies out.
//!
//! Verdict: with s_k the modal state at tooth pass k, the change over one tooth period
//! D_k = √Σ(Δq² + (Δq̇/ω)²) (Δ = s_k − s_{k−1}) is zero on a tooth-periodic motion. The cut
//! **chatters** when D does not die out: the largest D of the last quarter of the horizon
//! exceeds the largest of the second quarter (growth over half the horizon, as in the lobes'
//! time-domain criterion), or exceeds 10 × the largest D of the first four tooth periods (the
//! disturbance grew tenfold and then saturated when the teeth left the material). Otherwise,
//! or when D fell a millionfold from the first quarter to the last (settled to round-off), the
//! cut is **stable**.
//!
//! Spectrum: the amplitude spectrum ([`crate::spectrum`]) of the tip displacement over the last
//! half of the horizon, x and y combined, and that of the vibration *minus the steady cut*
//! (which removes the tooth-passing harmonics exactly). The chatter frequency is the largest
//! peak of the latter between half the lowest and twice the highest natural frequency. A peak
//! at an odd multiple of half the tooth-passing frequency (within 0.5 %) is a flip (period
//! doubling), any other a Hopf chatter. Sampled once per tooth, a vibration at f is one at any
//! alias k/τ ± f: semi-discretisation reports the alias nearest a natural frequency, the
//! simulated spectrum may peak at its mirror k/τ − f (the same once-per-tooth rotation).

use crate::params::Cut;
use crate::params::{positive, DynamicsError, TipModes, Tool};
use crate::sdm::BoundaryKind;
use crate::spectrum::Spectrum;
use crate::time_domain::{kind_of_frequency, ForceModel, Integrator, TimeDomain, TimeOptions};

/// Growth of D over its first four tooth periods above which a cut chatters.
pub const SATURATED_GROWTH: f64 = 10.0;
/// Decay of D from the first to the last quarter below which a cut has settled.
pub const SETTLED_DECAY: f64 = 1e-6;
/// Largest horizon in tooth periods (bounds memory: 64 steps × 5 values per step).
pub const MAX_TOOTH_PERIODS: usize = 100_000;

/// Options of a cut simulation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CutOptions {
    /// RK4 steps per tooth period m (default 64, at least 8): the error of the critical
    /// depth is below 1 % at 64 on the benchmark (see the lobes' time-domain tests).
    pub steps_per_tooth: usize,
    /// Horizon in tooth periods (default 400, at least 16): long enough to tell a disturbance
    /// that grows by a few tenths of a percent per tooth period from one that decays.
    pub tooth_periods: usize,
    /// Disturbance of every modal displacement at the start, m (default 1e-7 = 0.1 µm: far
    /// below a feed per tooth, so the disturbance stays in the linear range until it grows).
    pub disturbance_m: f64,
}

impl Default for CutOptions {
    fn default() -> Self {
        Self {
            steps_per_tooth: 64,
            tooth_periods: 400,
            disturbance_m: 1e-7,
        }
    }
}

/// Stable or chatter.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Verdict {
    /// A disturbance of the steady cut dies out.
    Stable,
    /// A disturbance of the steady cut grows (regenerative chatter).
    Chatter,
}

/// The steady cut: one tooth period of the tooth-periodic forced vibration.
#[derive(Debug, Clone, PartialEq)]
pub struct SteadyCut {
    /// Tip displacement [x, y] in m at the m steps of one tooth period (angle 0 first).
    pub displacement_m: Vec<[f64; 2]>,
}

/// Result of one simulated cut.
#[derive(Debug, Clone, PartialEq)]
pub struct CutSimulation {
    /// The cut.
    pub cut: Cut,
    /// Tooth period τ in s.
    pub period_s: f64,
    /// Integration step Δt = τ/m in s.
    pub step_s: f64,
    /// Disks of the helical flute (1 for straight teeth).
    pub disks: usize,
    /// Tip displacement [x, y] in m at t_i = iΔt, i = 0..steps.
    pub displacement_m: Vec<[f64; 2]>,
    /// Cutting force on the tool [F_x, F_y] in N at t_i.
    pub force_n: Vec<[f64; 2]>,
    /// The steady cut the simulation starts from.
    pub steady: SteadyCut,
    /// Change over one tooth period D_k in m at tooth passes k = 1..=K (index k − 1).
    pub change_per_tooth_m: Vec<f64>,
    /// Largest D of the last quarter over the largest of the second quarter.
    pub growth_ratio: f64,
    /// Largest D of the last quarter over the largest of the first four tooth periods.
    pub growth_from_start: f64,
    /// D fell a millionfold from the first quarter to the last: the cut settled to round-off.
    pub settled: bool,
    /// Stable or chatter (see the module's criterion).
    pub verdict: Verdict,
    /// Amplitude spectrum of the tip displacement (x and y combined, m) over the last half.
    pub spectrum: Spectrum,
    /// Amplitude spectrum of the tip displacement minus the steady cut, over the last half.
    pub disturbance_spectrum: Spectrum,
    /// Largest peak of `disturbance_spectrum` near the modes (Hz): the chatter frequency when
    /// the cut chatters, the decaying vibration's when it is stable.
    pub disturbance_peak_hz: Option<f64>,
    /// Hopf or flip, from the peak's place relative to the tooth-passing harmonics.
    pub disturbance_kind: Option<BoundaryKind>,
}

impl CutSimulation {
    /// Time t_i = iΔt in s of sample i.
    pub fn time_s(&self, i: usize) -> f64 {
        i as f64 * self.step_s
    }

    /// Chatter frequency in Hz, when the cut chatters.
    pub fn chatter_frequency_hz(&self) -> Option<f64> {
        match self.verdict {
            Verdict::Chatter => self.disturbance_peak_hz,
            Verdict::Stable => None,
        }
    }

    /// Hopf or flip, when the cut chatters.
    pub fn chatter_kind(&self) -> Option<BoundaryKind> {
        match self.verdict {
            Verdict::Chatter => self.disturbance_kind,
            Verdict::Stable => None,
        }
    }

    /// Largest vibration amplitude in m: [max |x|, max |y|, max √(x² + y²)].
    pub fn max_displacement_m(&self) -> [f64; 3] {
        max_abs(&self.displacement_m)
    }

    /// Largest forces in N: [max |F_x|, max |F_y|, max |F|].
    pub fn max_force_n(&self) -> [f64; 3] {
        max_abs(&self.force_n)
    }
}

fn max_abs(v: &[[f64; 2]]) -> [f64; 3] {
    v.iter().fold([0.0; 3], |m, p| {
        [
            m[0].max(p[0].abs()),
            m[1].max(p[1].abs()),
            m[2].max(p[0].hypot(p[1])),
        ]
    })
}

/// Checks the options.
fn validate(options: &CutOptions) -> Result<(), DynamicsError> {
    for (name, v, min) in [
        ("steps_per_tooth", options.steps_per_tooth, 8),
        ("tooth_periods", options.tooth_periods, 16),
    ] {
        if v < min {
            return Err(DynamicsError::TooFewSteps {
                name,
                min,
                value: v,
            });
        }
    }
    if options.tooth_periods > MAX_TOOTH_PERIODS {
        return Err(DynamicsError::TooManySteps {
            name: "tooth_periods",
            max: MAX_TOOTH_PERIODS,
            value: options.tooth_periods,
        });
    }
    positive("disturbance_m", options.disturbance_m)
}

/// Simulates one cut (see the module's model, start, verdict and spectrum).
///
/// # Errors
/// Invalid tool, modes, cut (a depth or feed of 0 is refused: nothing would be cut) or
/// options; [`DynamicsError::NoSteadyState`] for an undamped mode in resonance.
pub fn simulate_cut(
    tool: &Tool,
    modes: &TipModes,
    cut: &Cut,
    options: &CutOptions,
) -> Result<CutSimulation, DynamicsError> {
    cut.validate()?;
    positive("axial_depth_mm", cut.axial_depth_mm)?;
    positive("feed_per_tooth_mm", cut.feed_per_tooth_mm)?;
    validate(options)?;
    let td = TimeDomain::new(
        tool,
        modes,
        cut.immersion,
        cut.milling,
        TimeOptions {
            steps_per_tooth: options.steps_per_tooth,
            tooth_periods: options.tooth_periods,
            initial_displacement_m: options.disturbance_m,
        },
    )?;
    let mut run = Integrator::new(
        &td,
        cut.spindle_rpm,
        cut.axial_depth_mm,
        cut.feed_per_tooth_mm,
        ForceModel::Process,
    )?;
    let (_, orbit_m) = run.steady_state()?;
    let n = td.mode_count();
    for q in &mut run.s[..n] {
        *q += options.disturbance_m;
    }
    run.start();
    let m = run.m;
    let steps = m * options.tooth_periods;
    let mut displacement_m = Vec::with_capacity(steps);
    let mut force_n = Vec::with_capacity(steps);
    let mut change = Vec::with_capacity(options.tooth_periods);
    let mut last_pass = run.s.clone();
    let mut diff = vec![0.0; run.s.len()];
    for i in 0..steps {
        displacement_m.push(run.tip().0);
        force_n.push(run.step());
        if (i + 1) % m == 0 {
            for ((d, s), l) in diff.iter_mut().zip(&run.s).zip(&last_pass) {
                *d = s - l;
            }
            change.push(td.amplitude(&diff));
            last_pass.copy_from_slice(&run.s);
        }
    }
    let (growth_ratio, growth_from_start, settled, verdict) = judge(&change);
    let tail = steps / 2;
    let axis = |a: usize, steady: bool| -> Vec<f64> {
        (tail..steps)
            .map(|i| displacement_m[i][a] - if steady { orbit_m[i % m][a] } else { 0.0 })
            .collect()
    };
    let dt = run.dt;
    let spectrum = Spectrum::of(&axis(0, false), dt).combined(&Spectrum::of(&axis(1, false), dt));
    let disturbance_spectrum =
        Spectrum::of(&axis(0, true), dt).combined(&Spectrum::of(&axis(1, true), dt));
    let f = td.frequencies_hz();
    let f_lo = 0.5 * f.iter().cloned().fold(f64::INFINITY, f64::min);
    let f_hi = 2.0 * f.iter().cloned().fold(0.0, f64::max);
    let peak = disturbance_spectrum.peak(f_lo, f_hi).map(|(f, _)| f);
    Ok(CutSimulation {
        cut: *cut,
        period_s: run.period_s,
        step_s: dt,
        disks: run.disk_count(),
        displacement_m,
        force_n,
        steady: SteadyCut {
            displacement_m: orbit_m,
        },
        change_per_tooth_m: change,
        growth_ratio,
        growth_from_start,
        settled,
        verdict,
        spectrum,
        disturbance_spectrum,
        disturbance_peak_hz: peak,
        disturbance_kind: peak.map(|f| kind_of_frequency(f, run.period_s)),
    })
}

/// Growth ratio, growth from the start, settled and verdict from the changes per tooth
/// period.
fn judge(change: &[f64]) -> (f64, f64, bool, Verdict) {
    if change.iter().any(|d| !d.is_finite()) {
        return (f64::INFINITY, f64::INFINITY, false, Verdict::Chatter);
    }
    let len = change.len();
    let q = len / 4;
    let max = |s: &[f64]| s.iter().cloned().fold(0.0, f64::max);
    let (first, second, last) = (
        max(&change[..q]),
        max(&change[q..2 * q]),
        max(&change[len - q..]),
    );
    let start = max(&change[..4.min(len)]);
    let ratio = last / second;
    let from_start = last / start;
    let settled = last <= SETTLED_DECAY * first;
    let chatter = !settled && (ratio > 1.0 || from_start > SATURATED_GROWTH);
    (
        ratio,
        from_start,
        settled,
        if chatter {
            Verdict::Chatter
        } else {
            Verdict::Stable
        },
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_verdict_follows_the_change_per_tooth() {
        let decay: Vec<f64> = (0..400).map(|k| 0.99f64.powi(k)).collect();
        assert_eq!(judge(&decay).3, Verdict::Stable);
        let growth: Vec<f64> = (0..400).map(|k| 1.001f64.powi(k)).collect();
        assert_eq!(judge(&growth).3, Verdict::Chatter);
        // Grew 1000-fold in the first quarter, then saturated with a slight decline.
        let saturated: Vec<f64> = (0..400)
            .map(|k| {
                if k < 80 {
                    1.09f64.powi(k)
                } else {
                    1000.0 - k as f64
                }
            })
            .collect();
        assert_eq!(judge(&saturated).3, Verdict::Chatter);
        // Settled to round-off: noise at 1e-20 after a decay from 1 is stable.
        let settled: Vec<f64> = (0..400)
            .map(|k| {
                if k < 100 {
                    0.7f64.powi(k)
                } else {
                    1e-20 * (1.0 + (k % 3) as f64)
                }
            })
            .collect();
        assert_eq!(judge(&settled).3, Verdict::Stable);
        assert_eq!(judge(&[1.0, f64::NAN, 1.0, 1.0]).3, Verdict::Chatter);
    }
}
