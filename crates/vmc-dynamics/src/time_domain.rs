//! Time-domain simulation of milling with the regenerative delay.
//!
//! The modal equations of [`crate::modal`] are integrated with classical Runge–Kutta (RK4) on a
//! step Δt = τ/m (m = `steps_per_tooth`), so the delay τ is a whole number of steps. The delayed
//! tip displacement at a half step is the cubic Hermite interpolant of the stored displacement
//! and velocity (fourth-order consistent with RK4). The surface left before the start is the
//! undeformed one (zero history).
//!
//! Force per tooth j at angle φ_j (screen g(φ_j) of [`crate::forces`]):
//! h = f_z sinφ + (Δx sinφ + Δy cosφ), F_t = a_p(K_t h + K_te), F_n = a_p(K_n h + K_ne) +
//! (C a_p / v_c)(ẋ sinφ + ẏ cosφ), F_x = −F_t cosφ − F_n sinφ, F_y = F_t sinφ − F_n cosφ.
//! [`ForceModel::Process`] uses all terms and drops a tooth's force when h ≤ 0 (it left the
//! cut); [`ForceModel::Linear`] keeps only the regenerative and process-damping terms (no feed,
//! no edge forces, no loss of contact) — the linear delay equation that ZOA and SDM analyse.
//! With a helix the sum runs over the axial disks of [`crate::forces::Disks`] as well (each of
//! height a_p/K at its own lag, neighbours at most one step angle ωΔt apart).
//!
//! Instability criterion: in the linear model the vibration starts from a small initial
//! displacement and its amplitude A_k = √Σ(q² + (q̇/ω)²) is sampled once per tooth period
//! (Poincaré section, which removes the in-period variation); the cut is unstable when the
//! largest sample of the last quarter of the horizon exceeds the largest sample of the second
//! quarter (growth over half the horizon; default horizon 400 tooth periods). The chatter
//! frequency is the spectral peak of the last quarter's tip displacement.

use std::f64::consts::PI;

use nalgebra::{DMatrix, DVector};

use crate::forces::{cutting_speed_m_per_s, Disks, Engagement};
use crate::params::{
    non_negative, positive, validate_speed, DynamicsError, Milling, TipModes, Tool,
};
use crate::sdm::BoundaryKind;
use crate::sdm::LobePoint;

/// Force model of the simulation.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ForceModel {
    /// Regenerative and process-damping terms only, linear (for stability).
    Linear,
    /// Static feed, edge forces and loss of contact (the milling process).
    Process,
}

/// Options of the time-domain simulation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TimeOptions {
    /// Integration steps per tooth period (default 64; at least 8).
    pub steps_per_tooth: usize,
    /// Horizon in tooth periods (default 400; at least 8).
    pub tooth_periods: usize,
    /// Initial modal displacement in m for the linear model (default 1e-6).
    pub initial_displacement_m: f64,
}

impl Default for TimeOptions {
    fn default() -> Self {
        Self {
            steps_per_tooth: 64,
            tooth_periods: 400,
            initial_displacement_m: 1e-6,
        }
    }
}

/// Once-per-tooth samples of a simulation.
#[derive(Debug, Clone, PartialEq)]
pub struct Simulation {
    /// Tooth period τ in s (sample interval).
    pub period_s: f64,
    /// Tip displacement [x, y] in m at each tooth pass (index 0 = start).
    pub displacement_m: Vec<[f64; 2]>,
    /// Vibration amplitude √Σ(q² + (q̇/ω)²) in m at each tooth pass.
    pub amplitude_m: Vec<f64>,
    /// Integration steps taken.
    pub steps: usize,
    /// Integration step Δt in s.
    pub step_s: f64,
    /// Tip displacement [x, y] in m at every step of the last quarter of the horizon.
    pub tail_m: Vec<[f64; 2]>,
}

impl Simulation {
    /// Frequency in Hz of the largest peak of the tail's spectrum |X(f)|² + |Y(f)|² between
    /// `lo_hz` and `hi_hz`, by direct DFT on a grid as fine as 1/(4 × tail length), refined by
    /// a parabola through the peak and its neighbours.
    pub fn dominant_frequency_hz(&self, lo_hz: f64, hi_hz: f64) -> f64 {
        let len = self.tail_m.len();
        if len < 4 || hi_hz <= lo_hz {
            return 0.0;
        }
        let df = 0.25 / (len as f64 * self.step_s);
        let count = ((hi_hz - lo_hz) / df).ceil() as usize + 1;
        let power = |f: f64| {
            // Rotating phasor e^{−i2πfΔt k} by recurrence.
            let (s, c) = (-2.0 * PI * f * self.step_s).sin_cos();
            let (mut pr, mut pi) = (1.0, 0.0);
            let (mut xr, mut xi, mut yr, mut yi) = (0.0, 0.0, 0.0, 0.0);
            for v in &self.tail_m {
                xr += v[0] * pr;
                xi += v[0] * pi;
                yr += v[1] * pr;
                yi += v[1] * pi;
                let t = pr * c - pi * s;
                pi = pr * s + pi * c;
                pr = t;
            }
            xr * xr + xi * xi + yr * yr + yi * yi
        };
        let spectrum: Vec<f64> = (0..count).map(|k| power(lo_hz + df * k as f64)).collect();
        let (k, _) = spectrum
            .iter()
            .enumerate()
            .fold(
                (0, f64::NEG_INFINITY),
                |b, (k, v)| if *v > b.1 { (k, *v) } else { b },
            );
        let mut f = lo_hz + df * k as f64;
        if k > 0 && k + 1 < count {
            let (a, b, c) = (spectrum[k - 1], spectrum[k], spectrum[k + 1]);
            let den = a - 2.0 * b + c;
            if den < 0.0 {
                f += 0.5 * df * (a - c) / den;
            }
        }
        f
    }

    /// Ratio of the largest amplitude in the last quarter to that in the second quarter
    /// (infinite when the vibration overflowed).
    pub fn growth_ratio(&self) -> f64 {
        if self.amplitude_m.iter().any(|a| !a.is_finite()) {
            return f64::INFINITY;
        }
        let n = self.amplitude_m.len();
        let q = n / 4;
        let max = |s: &[f64]| s.iter().cloned().fold(0.0, f64::max);
        max(&self.amplitude_m[n - q..]) / max(&self.amplitude_m[q..2 * q])
    }
}

/// Cut-dependent constants of the force.
#[derive(Debug, Clone)]
pub(crate) struct Loads {
    /// Height of one disk a_p/K in m (the whole depth for straight teeth).
    disk_depth_m: f64,
    feed_m: f64,
    /// C·(a_p/K)/v_c, per disk.
    process_damping_n_s_per_m: f64,
    model: ForceModel,
    disks: Disks,
}

#[derive(Debug, Clone, Copy)]
struct ModeState {
    axis: usize,
    omega: f64,
    zeta: f64,
    mass_kg: f64,
}

/// Time-domain milling model for one tool, tip and engagement.
#[derive(Debug, Clone)]
pub struct TimeDomain {
    tool: Tool,
    window: Engagement,
    modes: Vec<ModeState>,
    options: TimeOptions,
}

impl TimeDomain {
    /// Validates the inputs.
    pub fn new(
        tool: &Tool,
        modes: &TipModes,
        immersion: f64,
        milling: Milling,
        options: TimeOptions,
    ) -> Result<Self, DynamicsError> {
        tool.validate()?;
        modes.validate()?;
        let window = Engagement::new(immersion, milling)?;
        for (name, v) in [
            ("steps_per_tooth", options.steps_per_tooth),
            ("tooth_periods", options.tooth_periods),
        ] {
            if v < 8 {
                return Err(DynamicsError::TooFewSteps {
                    name,
                    min: 8,
                    value: v,
                });
            }
        }
        positive("initial_displacement_m", options.initial_displacement_m)?;
        let list = modes
            .x
            .iter()
            .map(|m| (0, m))
            .chain(modes.y.iter().map(|m| (1, m)))
            .map(|(axis, m)| ModeState {
                axis,
                omega: m.omega_rad_per_s(),
                zeta: m.damping_ratio,
                mass_kg: m.modal_mass_kg(),
            })
            .collect();
        Ok(Self {
            tool: *tool,
            window,
            modes: list,
            options,
        })
    }

    /// The options given to [`TimeDomain::new`].
    pub fn options(&self) -> &TimeOptions {
        &self.options
    }

    /// Natural frequencies of the modes in Hz.
    pub fn frequencies_hz(&self) -> Vec<f64> {
        self.modes.iter().map(|m| m.omega / (2.0 * PI)).collect()
    }

    /// Number of modes (the state has twice as many entries).
    pub(crate) fn mode_count(&self) -> usize {
        self.modes.len()
    }

    fn tip(&self, s: &[f64]) -> ([f64; 2], [f64; 2]) {
        let n = self.modes.len();
        let (mut p, mut v) = ([0.0; 2], [0.0; 2]);
        for (k, m) in self.modes.iter().enumerate() {
            p[m.axis] += s[k];
            v[m.axis] += s[n + k];
        }
        (p, v)
    }

    /// Cutting force on the tool [F_x, F_y] in N, summed over disks and teeth.
    fn force(&self, phi: f64, p: [f64; 2], v: [f64; 2], delayed: [f64; 2], k: &Loads) -> [f64; 2] {
        let (a_m, feed_m, pd) = (k.disk_depth_m, k.feed_m, k.process_damping_n_s_per_m);
        let t = &self.tool;
        let mut f = [0.0; 2];
        for lag in k.disks.lags_rad() {
            for j in 0..t.teeth {
                let pj = phi + 2.0 * PI * f64::from(j) / f64::from(t.teeth) - lag;
                if self.window.screen(pj) == 0.0 {
                    continue;
                }
                let (s, c) = pj.sin_cos();
                let dh = (p[0] - delayed[0]) * s + (p[1] - delayed[1]) * c;
                let (ft, fn_) = match k.model {
                    ForceModel::Linear => (t.kt_n_per_m2 * a_m * dh, t.kn_n_per_m2 * a_m * dh),
                    ForceModel::Process => {
                        let h = feed_m * s + dh;
                        if h <= 0.0 {
                            continue;
                        }
                        (
                            a_m * (t.kt_n_per_m2 * h + t.kte_n_per_m),
                            a_m * (t.kn_n_per_m2 * h + t.kne_n_per_m),
                        )
                    }
                };
                let fn_ = fn_ + pd * (v[0] * s + v[1] * c);
                f[0] += -ft * c - fn_ * s;
                f[1] += ft * s - fn_ * c;
            }
        }
        f
    }

    /// State derivative; returns the cutting force [F_x, F_y] in N.
    fn deriv(
        &self,
        phi: f64,
        s: &[f64],
        delayed: [f64; 2],
        k: &Loads,
        out: &mut [f64],
    ) -> [f64; 2] {
        let n = self.modes.len();
        let (p, v) = self.tip(s);
        let f = self.force(phi, p, v, delayed, k);
        for (k, m) in self.modes.iter().enumerate() {
            out[k] = s[n + k];
            out[n + k] = -m.omega * m.omega * s[k] - 2.0 * m.zeta * m.omega * s[n + k]
                + f[m.axis] / m.mass_kg;
        }
        f
    }

    /// Vibration amplitude √Σ(q² + (q̇/ω)²) in m of a modal state.
    pub(crate) fn amplitude(&self, s: &[f64]) -> f64 {
        let n = self.modes.len();
        self.modes
            .iter()
            .enumerate()
            .map(|(k, m)| s[k] * s[k] + (s[n + k] / m.omega).powi(2))
            .sum::<f64>()
            .sqrt()
    }

    /// Simulates `tooth_periods` tooth passes at a speed, depth and feed with a force model
    /// (the engagement is the one given to [`TimeDomain::new`]).
    pub fn simulate(
        &self,
        spindle_rpm: f64,
        depth_mm: f64,
        feed_per_tooth_mm: f64,
        model: ForceModel,
    ) -> Result<Simulation, DynamicsError> {
        let mut run = Integrator::new(self, spindle_rpm, depth_mm, feed_per_tooth_mm, model)?;
        let (m, n) = (run.m, self.modes.len());
        if model == ForceModel::Linear {
            run.s[..n].fill(self.options.initial_displacement_m);
        }
        run.start();
        let mut out = Simulation {
            period_s: run.period_s,
            displacement_m: Vec::with_capacity(self.options.tooth_periods + 1),
            amplitude_m: Vec::with_capacity(self.options.tooth_periods + 1),
            steps: 0,
            step_s: run.dt,
            tail_m: Vec::with_capacity(self.options.tooth_periods * m / 4 + 1),
        };
        let tail_start = self.options.tooth_periods * m - self.options.tooth_periods * m / 4;
        out.displacement_m.push(run.tip().0);
        out.amplitude_m.push(self.amplitude(&run.s));
        for i in 0..self.options.tooth_periods * m {
            run.step();
            let p = run.tip().0;
            out.steps += 1;
            if i >= tail_start {
                out.tail_m.push(p);
            }
            if (i + 1) % m == 0 {
                out.displacement_m.push(p);
                out.amplitude_m.push(self.amplitude(&run.s));
            }
        }
        Ok(out)
    }

    /// Growth ratio of the linear model at a speed and depth (> 1: unstable).
    pub fn growth_ratio(&self, spindle_rpm: f64, depth_mm: f64) -> Result<f64, DynamicsError> {
        Ok(self
            .simulate(spindle_rpm, depth_mm, 0.0, ForceModel::Linear)?
            .growth_ratio())
    }

    /// True when the linear model's vibration does not grow over the horizon.
    pub fn is_stable(&self, spindle_rpm: f64, depth_mm: f64) -> Result<bool, DynamicsError> {
        Ok(self.growth_ratio(spindle_rpm, depth_mm)? <= 1.0)
    }

    /// Critical depth by bisection on (0, `max_depth_mm`] to `tol_mm`; `None` if stable at the
    /// maximum. Chatter frequency: spectral peak of the simulation just over the limit; kind:
    /// flip when that peak sits at an odd multiple of half the tooth-passing frequency.
    pub fn critical_depth(
        &self,
        spindle_rpm: f64,
        max_depth_mm: f64,
        tol_mm: f64,
    ) -> Result<Option<LobePoint>, DynamicsError> {
        positive("max_depth_mm", max_depth_mm)?;
        positive("tol_mm", tol_mm)?;
        if self.is_stable(spindle_rpm, max_depth_mm)? {
            return Ok(None);
        }
        let (mut lo, mut hi) = (0.0, max_depth_mm);
        while hi - lo > tol_mm {
            let mid = 0.5 * (lo + hi);
            if self.is_stable(spindle_rpm, mid)? {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        // Chatter frequency from the spectrum just over the limit; a flip shows as a peak at
        // an odd multiple of half the tooth-passing frequency (within 0.5 % of it).
        let sim = self.simulate(spindle_rpm, hi, 0.0, ForceModel::Linear)?;
        let f_min = self
            .modes
            .iter()
            .map(|m| m.omega)
            .fold(f64::INFINITY, f64::min)
            / (2.0 * PI);
        let f_max = self.modes.iter().map(|m| m.omega).fold(0.0, f64::max) / (2.0 * PI);
        let f = sim.dominant_frequency_hz(0.5 * f_min, 2.0 * f_max);
        let kind = kind_of_frequency(f, sim.period_s);
        Ok(Some(LobePoint {
            spindle_rpm,
            critical_depth_mm: 0.5 * (lo + hi),
            chatter_frequency_hz: f,
            kind,
            steps_per_period: Some(self.options.steps_per_tooth),
        }))
    }
}

/// Flip when a vibration at `frequency_hz` sits at an odd multiple of half the tooth-passing
/// frequency 1/τ (within 0.5 % of the frequency), else Hopf.
pub(crate) fn kind_of_frequency(frequency_hz: f64, period_s: f64) -> BoundaryKind {
    let half_harmonic = frequency_hz * period_s - 0.5;
    if (half_harmonic - half_harmonic.round()).abs() < 0.005 * frequency_hz * period_s {
        BoundaryKind::Flip
    } else {
        BoundaryKind::Hopf
    }
}

/// RK4 integration of one cut: modal state, delay buffer of one tooth period and scratch.
/// The delay τ is m steps; the spindle angle is taken within one tooth pitch.
pub(crate) struct Integrator<'a> {
    td: &'a TimeDomain,
    loads: Loads,
    /// Steps per tooth period.
    pub(crate) m: usize,
    /// Step Δt in s.
    pub(crate) dt: f64,
    /// Tooth period τ in s.
    pub(crate) period_s: f64,
    omega: f64,
    /// Modal state [q; q̇] at the current step.
    pub(crate) s: Vec<f64>,
    hist_p: Vec<[f64; 2]>,
    hist_v: Vec<[f64; 2]>,
    k: [Vec<f64>; 4],
    tmp: Vec<f64>,
    /// Steps taken.
    pub(crate) i: usize,
}

impl<'a> Integrator<'a> {
    /// A cut at rest with the undeformed surface as history. Helical teeth are cut into disks
    /// that lag by at most one step angle ωΔt.
    pub(crate) fn new(
        td: &'a TimeDomain,
        spindle_rpm: f64,
        depth_mm: f64,
        feed_per_tooth_mm: f64,
        model: ForceModel,
    ) -> Result<Self, DynamicsError> {
        validate_speed(spindle_rpm)?;
        non_negative("axial_depth_mm", depth_mm)?;
        non_negative("feed_per_tooth_mm", feed_per_tooth_mm)?;
        let m = td.options.steps_per_tooth;
        let period_s = td.tool.tooth_period_s(spindle_rpm);
        let dt = period_s / m as f64;
        let omega = 2.0 * PI * spindle_rpm / 60.0;
        let a_m = depth_mm * 1e-3;
        let disks = Disks::new(&td.tool, a_m, omega * dt);
        let count = disks.count() as f64;
        let loads = Loads {
            disk_depth_m: a_m / count,
            feed_m: feed_per_tooth_mm * 1e-3,
            process_damping_n_s_per_m: td.tool.process_damping_n_per_m * a_m
                / cutting_speed_m_per_s(&td.tool, spindle_rpm)
                / count,
            model,
            disks,
        };
        let dim = 2 * td.modes.len();
        Ok(Self {
            td,
            loads,
            m,
            dt,
            period_s,
            omega,
            s: vec![0.0; dim],
            hist_p: vec![[0.0; 2]; m + 1],
            hist_v: vec![[0.0; 2]; m + 1],
            k: std::array::from_fn(|_| vec![0.0; dim]),
            tmp: vec![0.0; dim],
            i: 0,
        })
    }

    /// Number of disks of the helical flute (1 for straight teeth).
    pub(crate) fn disk_count(&self) -> usize {
        self.loads.disks.count()
    }

    /// Current tip displacement and velocity [x, y] in m and m/s.
    pub(crate) fn tip(&self) -> ([f64; 2], [f64; 2]) {
        self.td.tip(&self.s)
    }

    /// Stores the current state as sample 0 of the delay buffer (call before the first step).
    pub(crate) fn start(&mut self) {
        let (p, v) = self.tip();
        let slot = (self.i + self.m) % (self.m + 1);
        self.hist_p[slot] = p;
        self.hist_v[slot] = v;
    }

    /// Sets the history of the last tooth period, sample j = −m + r from `past[r]`
    /// (r = 0..m, tip displacement and velocity), at step 0.
    pub(crate) fn set_history(&mut self, past_p: &[[f64; 2]], past_v: &[[f64; 2]]) {
        // Sample j sits in slot (j + m) mod (m + 1).
        self.hist_p[..self.m].copy_from_slice(&past_p[..self.m]);
        self.hist_v[..self.m].copy_from_slice(&past_v[..self.m]);
    }

    /// One RK4 step; returns the cutting force [F_x, F_y] in N at the start of the step.
    pub(crate) fn step(&mut self) -> [f64; 2] {
        let (m, dt, i) = (self.m, self.dt, self.i);
        // Slot of sample i − m (the oldest) is (i mod (m+1)); sample i−m+1 is the next slot.
        let old = i % (m + 1);
        let newer = (i + 1) % (m + 1);
        let (d0, d1) = (self.hist_p[old], self.hist_p[newer]);
        let (w0, w1) = (self.hist_v[old], self.hist_v[newer]);
        let mid = [
            0.5 * (d0[0] + d1[0]) + dt * (w0[0] - w1[0]) / 8.0,
            0.5 * (d0[1] + d1[1]) + dt * (w0[1] - w1[1]) / 8.0,
        ];
        // Teeth are identical, so the angle is taken within one tooth pitch: the same
        // angles recur bit for bit every tooth period (a tooth entering exactly on a step
        // boundary is then treated the same way at every pass).
        let phi = self.omega * dt * (i % m) as f64;
        let half = 0.5 * self.omega * dt;
        let (td, loads, s, tmp) = (self.td, &self.loads, &mut self.s, &mut self.tmp);
        let [k1, k2, k3, k4] = &mut self.k;
        let force = td.deriv(phi, s, d0, loads, k1);
        axpy(s, k1, 0.5 * dt, tmp);
        td.deriv(phi + half, tmp, mid, loads, k2);
        axpy(s, k2, 0.5 * dt, tmp);
        td.deriv(phi + half, tmp, mid, loads, k3);
        axpy(s, k3, dt, tmp);
        td.deriv(phi + 2.0 * half, tmp, d1, loads, k4);
        for r in 0..s.len() {
            s[r] += dt / 6.0 * (k1[r] + 2.0 * k2[r] + 2.0 * k3[r] + k4[r]);
        }
        // Sample i + 1 replaces the oldest one (i − m), which is no longer needed.
        let (p, v) = td.tip(s);
        self.hist_p[old] = p;
        self.hist_v[old] = v;
        self.i += 1;
        force
    }

    /// One RK4 step of the cut without regeneration (the delayed displacement is the current
    /// one, Δ = 0: the static chip f_z sinφ, edge forces and process damping) from `s` at step
    /// index `i`, in place.
    fn steady_step(&mut self, s: &mut [f64], i: usize) {
        let (td, loads, dt) = (self.td, &self.loads, self.dt);
        let phi = self.omega * dt * (i % self.m) as f64;
        let half = 0.5 * self.omega * dt;
        let tmp = &mut self.tmp;
        let [k1, k2, k3, k4] = &mut self.k;
        let d = |phi: f64, x: &[f64], out: &mut [f64]| {
            let p = td.tip(x).0;
            td.deriv(phi, x, p, loads, out);
        };
        d(phi, s, k1);
        axpy(s, k1, 0.5 * dt, tmp);
        d(phi + half, tmp, k2);
        axpy(s, k2, 0.5 * dt, tmp);
        d(phi + half, tmp, k3);
        axpy(s, k3, dt, tmp);
        d(phi + 2.0 * half, tmp, k4);
        for r in 0..s.len() {
            s[r] += dt / 6.0 * (k1[r] + 2.0 * k2[r] + 2.0 * k3[r] + k4[r]);
        }
    }

    /// The steady cut: the tooth-periodic forced vibration s*(t) = s*(t + τ) of the
    /// discretised structure under the static chip load (no regeneration). The map over one
    /// tooth period is affine, s ↦ M s + g; its fixed point s* = (I − M)⁻¹ g is found from
    /// 2n + 1 one-period runs. Puts the integrator on it (state s*, history one period of the
    /// orbit) and returns s* and the orbit's tip displacements at the m steps of one period.
    pub(crate) fn steady_state(&mut self) -> Result<(Vec<f64>, Vec<[f64; 2]>), DynamicsError> {
        let dim = self.s.len();
        let period_map = |me: &mut Self, s0: &[f64]| {
            let mut s = s0.to_vec();
            for i in 0..me.m {
                me.steady_step(&mut s, i);
            }
            s
        };
        let g = period_map(self, &vec![0.0; dim]);
        let mut i_minus_m = DMatrix::identity(dim, dim);
        for c in 0..dim {
            let mut e = vec![0.0; dim];
            e[c] = 1.0;
            let col = period_map(self, &e);
            for r in 0..dim {
                i_minus_m[(r, c)] -= col[r] - g[r];
            }
        }
        let fixed = i_minus_m
            .lu()
            .solve(&DVector::from_column_slice(&g))
            .filter(|x| x.iter().all(|v| v.is_finite()))
            .ok_or(DynamicsError::NoSteadyState)?;
        let fixed: Vec<f64> = fixed.iter().copied().collect();
        let mut s = fixed.clone();
        let (mut orbit_p, mut orbit_v) = (Vec::with_capacity(self.m), Vec::with_capacity(self.m));
        for i in 0..self.m {
            let (p, v) = self.td.tip(&s);
            orbit_p.push(p);
            orbit_v.push(v);
            self.steady_step(&mut s, i);
        }
        self.s.copy_from_slice(&fixed);
        self.i = 0;
        self.set_history(&orbit_p, &orbit_v);
        self.start();
        Ok((fixed, orbit_p))
    }
}

fn axpy(x: &[f64], k: &[f64], h: f64, out: &mut [f64]) {
    for ((o, a), b) in out.iter_mut().zip(x).zip(k) {
        *o = a + h * b;
    }
}
