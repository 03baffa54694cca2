//! Features of the readings' history: what a compensator can know of the machine's thermal past
//! from the sensor readings it has seen, beyond the present readings.
//!
//! Model: each sensor's reading `x(t)` feeds first-order low-pass filters
//! `τ·dy/dt = x − y` with time constants `τ` (s). The feature of sensor `i` and filter `τ` is
//! `x_i − y_{i,τ}`: zero at a thermal steady state, positive while the reading rises faster than
//! the filter follows (heating), negative while it falls (cooling). A structure whose temperature
//! lags a measured one by roughly `τ` (an unmeasured bearing seat, a screw under a swinging
//! ambient) is seen through it. The readings are taken as linear between samples (first-order
//! hold), so the exact update over a gap `h`, with `a = e^(−h/τ)` and slope `s = (x₁ − x₀)/h`, is
//! `y₁ = a·y₀ + (1 − a)·x₀ + s·(h − τ(1 − a))`: the same features whether the readings arrive
//! every second (in the loop) or every few minutes (in a calibration log), up to how linear the
//! readings are between samples.
//!
//! The filters start at the first reading, i.e. the machine is assumed at a thermal steady state
//! when logging starts (a calibration cycle from a cold machine, a controller switched on with
//! the machine). Units: s and °C (features in K).

/// The first time constant of `taus_s` that a filter cannot use (not finite, or ≤ 0 s), if any.
pub fn invalid_tau(taus_s: &[f64]) -> Option<f64> {
    taus_s
        .iter()
        .copied()
        .find(|t| !(t.is_finite() && *t > 0.0))
}

/// Largest heat-input exponent of a speed accepted: friction heat grows at most with the cube of
/// the speed, and higher powers of a real speed overflow.
pub const MAX_SPEED_EXPONENT: f64 = 10.0;

/// The first heat-input exponent of `exponents` outside (0, [`MAX_SPEED_EXPONENT`]] (or not
/// finite), if any.
pub fn invalid_speed_exponent(exponents: &[f64]) -> Option<f64> {
    exponents
        .iter()
        .copied()
        .find(|e| !(e.is_finite() && *e > 0.0 && *e <= MAX_SPEED_EXPONENT))
}

/// Filter state over a stream of readings of `n` sensors, of which some are filtered.
#[derive(Debug, Clone, PartialEq)]
pub struct ReadingHistory {
    taus_s: Vec<f64>,
    n: usize,
    /// Indices of the filtered sensors.
    idx: Vec<usize>,
    /// Filter outputs, `[tau][filtered sensor]` row-major.
    filtered: Vec<f64>,
    last_x: Vec<f64>,
    last_t_s: f64,
    started: bool,
}

impl ReadingHistory {
    /// Filters with time constants `taus_s` (s, each > 0) over every one of `n_sensors`
    /// readings.
    pub fn new(taus_s: &[f64], n_sensors: usize) -> Self {
        Self::of_sensors(taus_s, n_sensors, &(0..n_sensors).collect::<Vec<_>>())
    }

    /// Filters with time constants `taus_s` over the readings `filtered` (indices < `n_sensors`,
    /// others ignored) of `n_sensors`.
    pub fn of_sensors(taus_s: &[f64], n_sensors: usize, filtered: &[usize]) -> Self {
        let idx: Vec<usize> = filtered
            .iter()
            .copied()
            .filter(|&i| i < n_sensors)
            .collect();
        Self {
            taus_s: taus_s.to_vec(),
            n: n_sensors,
            filtered: vec![0.0; taus_s.len() * idx.len()],
            idx,
            last_x: vec![0.0; n_sensors],
            last_t_s: 0.0,
            started: false,
        }
    }

    /// Features: `n_sensors + n_filtered × n_taus` (the readings, then one block per filter).
    pub fn n_features(n_sensors: usize, n_filtered: usize, n_taus: usize) -> usize {
        n_sensors + n_filtered * n_taus
    }

    /// Features of this history ([`Self::n_features`]).
    pub fn len(&self) -> usize {
        Self::n_features(self.n, self.idx.len(), self.taus_s.len())
    }

    /// Whether there are no features at all (no sensor).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Takes the readings `x` (°C) at time `t_s`. Readings at or before the last one's time, or
    /// with a non-finite value, are ignored (held readings are passed again and again).
    pub fn observe(&mut self, t_s: f64, x: &[f64]) {
        if x.len() != self.n || !t_s.is_finite() || x.iter().any(|v| !v.is_finite()) {
            return;
        }
        let m = self.idx.len();
        if !self.started {
            for row in self.filtered.chunks_exact_mut(m.max(1)) {
                for (y, &i) in row.iter_mut().zip(&self.idx) {
                    *y = x[i];
                }
            }
            self.last_x.copy_from_slice(x);
            self.last_t_s = t_s;
            self.started = true;
            return;
        }
        let h = t_s - self.last_t_s;
        if h <= 0.0 {
            return;
        }
        for (k, &tau) in self.taus_s.iter().enumerate() {
            let a = (-h / tau).exp();
            let ramp = h - tau * (1.0 - a);
            let row = &mut self.filtered[k * m..(k + 1) * m];
            for (y, &i) in row.iter_mut().zip(&self.idx) {
                let (x0, x1) = (self.last_x[i], x[i]);
                let s = (x1 - x0) / h;
                *y = a * *y + (1.0 - a) * x0 + s * ramp;
            }
        }
        self.last_x.copy_from_slice(x);
        self.last_t_s = t_s;
    }

    /// Number of history features (`x_i − y_{i,τ}` per filtered sensor and filter).
    pub fn n_history(&self) -> usize {
        self.idx.len() * self.taus_s.len()
    }

    /// Writes the features of readings `x` (the present ones, °C) into `out`
    /// ([`Self::len`] values): `x`, then `x_i − y_{i,τ}` of the filtered sensors per filter.
    /// Before any reading the filters are taken at `x` (steady state).
    pub fn features_into(&self, x: &[f64], out: &mut [f64]) {
        let n = self.n;
        out[..n].copy_from_slice(x);
        self.history_into(x, &mut out[n..]);
    }

    /// Writes only the history part of [`Self::features_into`] ([`Self::n_history`] values).
    pub fn history_into(&self, x: &[f64], out: &mut [f64]) {
        let m = self.idx.len();
        for k in 0..self.taus_s.len() {
            let o = &mut out[k * m..(k + 1) * m];
            if self.started {
                let row = &self.filtered[k * m..(k + 1) * m];
                for ((f, &i), &yi) in o.iter_mut().zip(&self.idx).zip(row) {
                    *f = x[i] - yi;
                }
            } else {
                o.fill(0.0);
            }
        }
    }
}

/// Heat-input features of the commanded spindle speed: what a controller knows of the heat the
/// spindle put in, beyond what its temperature sensors show (the bearings, where the heat is
/// made, carry no sensor).
///
/// The speed is logged as *the speed the spindle ran at since the previous log* (rpm; 0 when
/// stopped), so a step between two logs falls at a log. For each exponent `e` the heat input is
/// `q_e = (n / 1000 rpm)^e` (bearing friction heat grows between linearly and with the cube of
/// the speed), held constant between logs, and the features are `q_e` itself (the present
/// duty: running or stopped) and its first-order low-pass filters `τ·dy/dt = q_e − y` per time
/// constant `τ` (the temperature rise of a part with that time constant driven by that heat),
/// updated exactly for the held input: `y₁ = a·y₀ + (1 − a)·q_e`, `a = e^(−h/τ)`. The filters
/// start at zero at the first log: the spindle at rest for long before logging starts (a cold
/// machine, a controller switched on with it). Units: s, rpm; features dimensionless.
#[derive(Debug, Clone, PartialEq)]
pub struct SpeedHistory {
    exponents: Vec<f64>,
    taus_s: Vec<f64>,
    /// Filter outputs, `[exponent][tau]` row-major.
    filtered: Vec<f64>,
    /// Heat inputs of the last logged interval, per exponent.
    last_q: Vec<f64>,
    last_t_s: f64,
    started: bool,
}

impl SpeedHistory {
    /// Features of `exponents` (each in (0, [`MAX_SPEED_EXPONENT`]]) through filters of `taus_s`
    /// (each > 0 s).
    pub fn new(exponents: &[f64], taus_s: &[f64]) -> Self {
        Self {
            exponents: exponents.to_vec(),
            taus_s: taus_s.to_vec(),
            filtered: vec![0.0; exponents.len() * taus_s.len()],
            last_q: vec![0.0; exponents.len()],
            last_t_s: 0.0,
            started: false,
        }
    }

    /// Number of features: per exponent, the present input and one filter per time constant.
    pub fn n_features(n_exponents: usize, n_taus: usize) -> usize {
        n_exponents * (1 + n_taus)
    }

    /// Features of this history ([`Self::n_features`]).
    pub fn len(&self) -> usize {
        Self::n_features(self.exponents.len(), self.taus_s.len())
    }

    /// Whether there are no features (no exponent).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The spindle ran at `rpm` since the previous log, up to `t_s`. A log at or before the
    /// previous one's time, or with a speed that is not finite, is ignored.
    pub fn observe(&mut self, t_s: f64, rpm: f64) {
        if !t_s.is_finite() || !rpm.is_finite() {
            return;
        }
        if !self.started {
            self.started = true;
            self.last_t_s = t_s;
            return;
        }
        let h = t_s - self.last_t_s;
        if h <= 0.0 {
            return;
        }
        for (q, &e) in self.last_q.iter_mut().zip(&self.exponents) {
            *q = (rpm.abs() / 1000.0).powf(e);
        }
        let nt = self.taus_s.len();
        for (j, &tau) in self.taus_s.iter().enumerate() {
            let a = (-h / tau).exp();
            for (k, &q) in self.last_q.iter().enumerate() {
                let y = &mut self.filtered[k * nt + j];
                *y = a * *y + (1.0 - a) * q;
            }
        }
        self.last_t_s = t_s;
    }

    /// Writes the features into `out` ([`Self::len`] values): per exponent, the present input,
    /// then its filters.
    pub fn features_into(&self, out: &mut [f64]) {
        let nt = self.taus_s.len();
        for (k, o) in out.chunks_exact_mut(1 + nt).enumerate() {
            o[0] = self.last_q[k];
            o[1..].copy_from_slice(&self.filtered[k * nt..(k + 1) * nt]);
        }
    }
}

/// Heat-input features of the axes' commanded feeds: per axis X, Y, Z, the first-order filters
/// (each time constant) of the mean |speed| in m/min (the heat a screw's nut and bearings and
/// the motor take in grows about in proportion to it), the way [`SpeedHistory`] treats the
/// spindle speed (exponent 1: `v / 1000 mm/min`). The present speed itself is not a feature:
/// a test's own short moves would weigh like hours of duty.
#[derive(Debug, Clone, PartialEq)]
pub struct FeedHistory {
    axes: [SpeedHistory; 3],
}

impl FeedHistory {
    /// Features through filters of `taus_s` (each > 0 s); none with no time constant.
    pub fn new(taus_s: &[f64]) -> Self {
        let exponents: &[f64] = if taus_s.is_empty() { &[] } else { &[1.0] };
        let axis = || SpeedHistory::new(exponents, taus_s);
        Self {
            axes: [axis(), axis(), axis()],
        }
    }

    /// Number of features for `n_taus` time constants: 3 × n_taus.
    pub fn n_features(n_taus: usize) -> usize {
        3 * n_taus
    }

    /// Features of this history.
    pub fn len(&self) -> usize {
        self.axes.iter().map(|a| a.len().saturating_sub(1)).sum()
    }

    /// Whether there are no features.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The axes ran at mean speeds `feeds_mm_per_min` since the previous log, up to `t_s`.
    pub fn observe(&mut self, t_s: f64, feeds_mm_per_min: [f64; 3]) {
        for (h, f) in self.axes.iter_mut().zip(feeds_mm_per_min) {
            h.observe(t_s, f);
        }
    }

    /// Writes the features into `out` ([`Self::len`] values): X's, then Y's, then Z's.
    pub fn features_into(&self, out: &mut [f64]) {
        let n = self.axes[0].len();
        if n == 0 {
            return;
        }
        let mut all = [0.0; 16];
        for (h, o) in self.axes.iter().zip(out.chunks_exact_mut(n - 1)) {
            // With the present input first (at most 15 filters: `MAX_FEED_TAUS`).
            h.features_into(&mut all[..n]);
            o.copy_from_slice(&all[1..n]);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn feed_features_are_per_axis_inputs_and_their_filters() {
        let mut h = FeedHistory::new(&[600.0]);
        assert_eq!(h.len(), 3);
        h.observe(0.0, [0.0; 3]);
        for k in 1..=10_000 {
            h.observe(f64::from(k), [0.0, 2000.0, 6000.0]);
        }
        let mut f = [9.0; 3];
        h.features_into(&mut f);
        // Settled after many τ (e^-16.7): each filter equals its input (m/min).
        assert_eq!(f[0], 0.0);
        assert!(
            (f[1] - 2.0).abs() < 1e-6 && (f[2] - 6.0).abs() < 1e-6,
            "{f:?}"
        );
        assert!(FeedHistory::new(&[]).is_empty());
        assert_eq!(FeedHistory::n_features(0), 0);
    }

    #[test]
    fn a_constant_reading_gives_zero_history_features() {
        let mut h = ReadingHistory::new(&[600.0, 3600.0], 2);
        let mut f = [1.0; 6];
        for k in 0..100 {
            h.observe(k as f64 * 17.0, &[21.0, 25.5]);
        }
        h.features_into(&[21.0, 25.5], &mut f);
        assert_eq!(f, [21.0, 25.5, 0.0, 0.0, 0.0, 0.0]);
    }

    #[test]
    fn a_ramp_settles_at_rate_times_tau_whatever_the_sampling() {
        // x = 20 + r·t: the filter lags by r·τ once settled (after many τ).
        let r = 1e-3;
        let tau = 600.0;
        for dt in [1.0, 60.0, 300.0, 1000.0] {
            let mut h = ReadingHistory::new(&[tau], 1);
            let mut t = 0.0;
            while t <= 20.0 * tau {
                h.observe(t, &[20.0 + r * t]);
                t += dt;
            }
            let t_last = t - dt;
            let mut f = [0.0; 2];
            h.features_into(&[20.0 + r * t_last], &mut f);
            assert!((f[1] - r * tau).abs() < 1e-8, "dt {dt}: {}", f[1]);
        }
    }

    #[test]
    fn a_step_decays_with_the_time_constant() {
        // Samples 1 s apart: the step happens over the first second (linear between samples).
        let tau = 100.0;
        let mut h = ReadingHistory::new(&[tau], 1);
        h.observe(0.0, &[0.0]);
        h.observe(1.0, &[1.0]);
        h.observe(1.0 + tau, &[1.0]);
        let mut f = [0.0; 2];
        h.features_into(&[1.0], &mut f);
        // After the ramp over [0, 1] s the filter is ≈ 1/(2τ); then 1 − y decays by e^-1.
        let y1 = 1.0 - tau * (1.0 - (-1.0 / tau).exp());
        let expected = (1.0 - y1) * (-1.0f64).exp();
        assert!((f[1] - expected).abs() < 1e-12, "{} vs {expected}", f[1]);
    }

    #[test]
    fn stale_or_broken_readings_are_ignored_and_the_start_is_steady() {
        let mut h = ReadingHistory::new(&[60.0], 1);
        let mut f = [0.0; 2];
        h.features_into(&[30.0], &mut f);
        assert_eq!(f, [30.0, 0.0]);
        h.observe(10.0, &[20.0]);
        h.observe(10.0, &[50.0]);
        h.observe(5.0, &[50.0]);
        h.observe(20.0, &[f64::NAN]);
        h.observe(20.0, &[20.0, 1.0]);
        h.features_into(&[20.0], &mut f);
        assert_eq!(f, [20.0, 0.0]);
    }

    #[test]
    fn only_the_chosen_sensors_are_filtered() {
        let mut h = ReadingHistory::of_sensors(&[100.0], 3, &[2, 7]);
        assert_eq!(h.len(), 4);
        h.observe(0.0, &[1.0, 2.0, 3.0]);
        h.observe(100.0, &[1.0, 2.0, 5.0]);
        let mut f = [0.0; 4];
        h.features_into(&[1.0, 2.0, 5.0], &mut f);
        assert_eq!(&f[..3], &[1.0, 2.0, 5.0]);
        // A ramp of 2 K over τ: y = 3 + 2·(1 − (1 − e^-1)) = 3 + 2/e.
        let expected = 2.0 - 2.0 * (-1.0f64).exp();
        assert!((f[3] - expected).abs() < 1e-12, "{f:?}");
    }

    #[test]
    fn speed_features_are_first_order_responses_to_the_held_heat_input() {
        let tau = 600.0;
        let mut h = SpeedHistory::new(&[1.0, 2.0], &[tau]);
        assert_eq!(h.len(), 4);
        h.observe(0.0, 0.0);
        // 2000 rpm for 600 s, logged every 60 s: q1 = 2, q2 = 4; y = q (1 − e^-1).
        for k in 1..=10 {
            h.observe(60.0 * k as f64, 2000.0);
        }
        let mut f = [0.0; 4];
        h.features_into(&mut f);
        let g = 1.0 - (-1.0f64).exp();
        assert!(
            (f[0] - 2.0).abs() < 1e-12 && (f[2] - 4.0).abs() < 1e-12,
            "{f:?}"
        );
        assert!((f[1] - 2.0 * g).abs() < 1e-12, "{f:?}");
        assert!((f[3] - 4.0 * g).abs() < 1e-12, "{f:?}");
        // Stopped for one τ, logged once: the present input is zero, the filter decays by e^-1.
        h.observe(600.0 + tau, 0.0);
        h.features_into(&mut f);
        assert_eq!(f[0], 0.0);
        assert!((f[1] - 2.0 * g * (-1.0f64).exp()).abs() < 1e-12, "{f:?}");
        // Stale or broken logs change nothing.
        let before = h.clone();
        h.observe(600.0 + tau, 9000.0);
        h.observe(0.0, 9000.0);
        h.observe(1e9, f64::NAN);
        assert_eq!(h, before);
    }
}
