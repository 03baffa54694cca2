//! The drift the model misses as a linear field over the working volume, estimated from probed
//! artefacts at several places: per error component `k`, `d_k(q) = b_k + g_k · (q − q₀)` with an
//! offset `b_k` (mm) and a gradient `g_k` (mm per mm) about a centre `q₀` (mm, the artefacts'
//! centroid, fixed when the filter is made); the offset moves on with a fading rate `v_k`.
//!
//! **Why a field.** One artefact sees the residual at one place; the residual of a warm machine
//! varies over the volume (a tilt of the spindle head makes `Ex` change with `Z`, an expansion
//! the model under-predicts makes `Ez` change along an axis), and an offset measured in one
//! corner applied everywhere can double the error in the opposite corner. Artefacts at four
//! places not in one plane determine the whole first-order field.
//!
//! **Why a fading rate.** Probing stops the spindle, and in the minutes after a stop the model's
//! residual moves fast (the spindle's front bearing cools, which no sensor sees in time: several
//! µm in 5 min on the reference machine). The offset measured during a cycle is already behind
//! when the work resumes. A rate that persists would run away over the hour to the next cycle; a
//! rate that fades with a time constant `τ` (an Ornstein–Uhlenbeck process, stationary σ
//! `rate_sigma`) carries the offset on by at most `v·τ`, and is seen by touching the same
//! artefacts twice in a cycle.
//!
//! **Estimator**, stated: per component an independent Kalman filter of the state
//! `x_k = [b_k, g_kx, g_ky, g_kz, v_k]`: `b` and each gradient random walks (`b` by
//! `walk_offset` µm/√h, each gradient by `walk_gradient` µm per metre per √h); over `Δt`,
//! `b ← b + v·τ·(1 − e^(−Δt/τ))`, `v ← v·e^(−Δt/τ)` with the rate's noise keeping its
//! stationary variance. The initial state is 0 with σ `initial_offset` µm, `initial_gradient`
//! µm/m and `rate_sigma`. A measurement of component `k` at axis position `p` and time `t` is
//! `y = b_k + g_k · (p − q₀) + v`, `v ~ N(0, r)`: each scalar measurement is one update with
//! `H = [1, p − q₀, 0]` after the prediction to `t`. The gradient's prior keeps it near 0 where
//! the artefacts do not see it (all artefacts at one height: no Z gradient). Between updates the
//! field is forecast to the time last observed ([`DriftField::observe_time`]).
//!
//! Units: mm, mm/mm, mm/s and s in the state; µm, µm/m, µm/min and hours in the settings where
//! the names say so.

use nalgebra::{SMatrix, SVector};

/// State of one component: offset, three gradient terms, the offset's rate.
type State = SVector<f64, 5>;
/// Its covariance.
type Cov = SMatrix<f64, 5, 5>;

use super::DriftSettingError;

/// Settings of a [`DriftField`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FieldSettings {
    /// Random walk of each offset, µm per √h.
    pub walk_offset_um_per_sqrt_h: f64,
    /// Random walk of each gradient term, µm per metre per √h.
    pub walk_gradient_um_per_m_sqrt_h: f64,
    /// σ of one scalar measurement, µm.
    pub measurement_sigma_um: f64,
    /// σ of the offset before any probing, µm.
    pub initial_offset_um: f64,
    /// σ of each gradient term before any probing, µm/m.
    pub initial_gradient_um_per_m: f64,
    /// Stationary σ of the offset's rate, µm per minute (a tiny value: no rate).
    pub rate_sigma_um_per_min: f64,
    /// Time in which the rate fades, s.
    pub rate_tau_s: f64,
}

impl FieldSettings {
    fn check(&self) -> Result<(), DriftSettingError> {
        for (field, value) in [
            ("walk_offset_um_per_sqrt_h", self.walk_offset_um_per_sqrt_h),
            (
                "walk_gradient_um_per_m_sqrt_h",
                self.walk_gradient_um_per_m_sqrt_h,
            ),
            ("measurement_sigma_um", self.measurement_sigma_um),
            ("initial_offset_um", self.initial_offset_um),
            ("initial_gradient_um_per_m", self.initial_gradient_um_per_m),
            ("rate_sigma_um_per_min", self.rate_sigma_um_per_min),
            ("rate_tau_s", self.rate_tau_s),
        ] {
            if !(value.is_finite() && value > 0.0) {
                return Err(DriftSettingError { field, value });
            }
        }
        Ok(())
    }
}

/// The offset-and-gradient drift filter with a fading rate of the offset (module doc).
#[derive(Debug, Clone, PartialEq)]
pub struct DriftField {
    centre_mm: [f64; 3],
    /// Walk rate of the offset and the gradient terms per component, mm² (or (mm/mm)²) per s;
    /// the rate's entry is unused (its noise follows from its stationary variance).
    walk_per_s: [State; 3],
    /// Stationary variance of the rate, (mm/s)².
    rate_var: f64,
    rate_tau_s: f64,
    /// Variance of one scalar measurement per component, mm².
    measurement_mm2: [f64; 3],
    state: [State; 3],
    cov: [Cov; 3],
    /// Time the state refers to, s (None before the first update).
    updated_s: Option<f64>,
    /// Latest time observed, s (the forecast's time).
    now_s: Option<f64>,
}

impl DriftField {
    /// A field about `centre_mm` with `settings`.
    ///
    /// # Errors
    /// A setting that is not finite and > 0, or a centre that is not finite.
    pub fn new(centre_mm: [f64; 3], settings: &FieldSettings) -> Result<Self, DriftSettingError> {
        settings.check()?;
        if let Some(&value) = centre_mm.iter().find(|v| !v.is_finite()) {
            return Err(DriftSettingError {
                field: "centre_mm",
                value,
            });
        }
        let mm2 = |um: f64| (um * 1e-3).powi(2);
        // A gradient of 1 µm/m is 1e-6 mm/mm.
        let grad2 = |um_per_m: f64| (um_per_m * 1e-6).powi(2);
        let g_walk = grad2(settings.walk_gradient_um_per_m_sqrt_h);
        let walk_per_s = State::from([
            mm2(settings.walk_offset_um_per_sqrt_h),
            g_walk,
            g_walk,
            g_walk,
            0.0,
        ]) / 3600.0;
        let rate_var = (settings.rate_sigma_um_per_min * 1e-3 / 60.0).powi(2);
        let g0 = grad2(settings.initial_gradient_um_per_m);
        let p0 = Cov::from_diagonal(&State::from([
            mm2(settings.initial_offset_um),
            g0,
            g0,
            g0,
            rate_var,
        ]));
        Ok(DriftField {
            centre_mm,
            walk_per_s: [walk_per_s; 3],
            rate_var,
            rate_tau_s: settings.rate_tau_s,
            measurement_mm2: [mm2(settings.measurement_sigma_um); 3],
            state: [State::zeros(); 3],
            cov: [p0; 3],
            updated_s: None,
            now_s: None,
        })
    }

    /// The transition of component `k` over `dt_s`: `(F, Q)`.
    fn transition(&self, k: usize, dt_s: f64) -> (Cov, Cov) {
        let fade = (-dt_s / self.rate_tau_s).exp();
        let mut f = Cov::identity();
        f[(0, 4)] = self.rate_tau_s * (1.0 - fade);
        f[(4, 4)] = fade;
        let mut q = Cov::from_diagonal(&(self.walk_per_s[k] * dt_s));
        q[(4, 4)] = self.rate_var * (1.0 - fade * fade);
        (f, q)
    }

    /// Sets the prior of one gradient term, component `k`'s gradient along `axis` (0 X, 1 Y,
    /// 2 Z): its σ before any probing, `initial_um_per_m` µm/m, and its random walk,
    /// `walk_um_per_m_sqrt_h` µm/m per √h. A regularised field: the terms the artefacts see
    /// well and the machine is known to show get a prior of their size, the others stay near 0.
    ///
    /// Meant before the first update; later it resets the term's variance (its covariance with
    /// the other terms dropped) and sets its walk from then on.
    ///
    /// # Errors
    /// A value that is not finite and > 0, or a component or axis beyond 2.
    pub fn set_gradient_prior(
        &mut self,
        k: usize,
        axis: usize,
        initial_um_per_m: f64,
        walk_um_per_m_sqrt_h: f64,
    ) -> Result<(), DriftSettingError> {
        for (field, value) in [("component", k), ("axis", axis)] {
            if value > 2 {
                return Err(DriftSettingError {
                    field,
                    value: value as f64,
                });
            }
        }
        for (field, value) in [
            ("initial_gradient_um_per_m", initial_um_per_m),
            ("walk_gradient_um_per_m_sqrt_h", walk_um_per_m_sqrt_h),
        ] {
            if !(value.is_finite() && value > 0.0) {
                return Err(DriftSettingError { field, value });
            }
        }
        let i = 1 + axis;
        // The term's row and column are its variance alone (independent of the other terms).
        self.cov[k].row_mut(i).fill(0.0);
        self.cov[k].column_mut(i).fill(0.0);
        self.cov[k][(i, i)] = (initial_um_per_m * 1e-6).powi(2);
        self.walk_per_s[k][i] = (walk_um_per_m_sqrt_h * 1e-6).powi(2) / 3600.0;
        Ok(())
    }

    /// Sets the σ of one measurement of component `k` (0 X, 1 Y, 2 Z) to `sigma_um` µm, when
    /// the components are measured with different care (more touches along Z).
    ///
    /// # Errors
    /// A σ that is not finite and > 0, or a component beyond 2.
    pub fn set_measurement_sigma_um(
        &mut self,
        k: usize,
        sigma_um: f64,
    ) -> Result<(), DriftSettingError> {
        if k > 2 {
            return Err(DriftSettingError {
                field: "component",
                value: k as f64,
            });
        }
        if !(sigma_um.is_finite() && sigma_um > 0.0) {
            return Err(DriftSettingError {
                field: "measurement_sigma_um",
                value: sigma_um,
            });
        }
        self.measurement_mm2[k] = (sigma_um * 1e-3).powi(2);
        Ok(())
    }

    /// Notes the present time, s: [`Self::drift_at_mm`] forecasts the state to it.
    pub fn observe_time(&mut self, time_s: f64) {
        if time_s.is_finite() {
            self.now_s = Some(time_s);
        }
    }

    /// The state of component `k` forecast to the time last observed.
    fn forecast(&self, k: usize) -> State {
        let dt_s = match (self.updated_s, self.now_s) {
            (Some(u), Some(n)) if n > u => n - u,
            _ => return self.state[k],
        };
        self.transition(k, dt_s).0 * self.state[k]
    }

    /// The estimated drift at axis position `q_mm`, mm per component (what
    /// [`super::WithDrift`] adds to the prediction), forecast to the time last observed.
    #[inline]
    pub fn drift_at_mm(&self, q_mm: [f64; 3]) -> [f64; 3] {
        let d = [0, 1, 2].map(|a| q_mm[a] - self.centre_mm[a]);
        [0, 1, 2].map(|k| {
            let x = self.forecast(k);
            x[0] + x[1] * d[0] + x[2] * d[1] + x[3] * d[2]
        })
    }

    /// The offset per component at the last update, mm (the drift at the centre).
    pub fn offset_mm(&self) -> [f64; 3] {
        self.state.map(|x| x[0])
    }

    /// The offset's rate per component at the last update, mm per s.
    pub fn rate_mm_per_s(&self) -> [f64; 3] {
        self.state.map(|x| x[4])
    }

    /// The gradient of component `k` (0 X, 1 Y, 2 Z) along X, Y, Z, mm per mm.
    pub fn gradient(&self, k: usize) -> [f64; 3] {
        let x = self.state[k.min(2)];
        [x[1], x[2], x[3]]
    }

    /// One probing cycle's measurements at time `time_s` (s): each `(component, at_mm,
    /// drift_mm)` says the drift of that component at axis position `at_mm` was measured as
    /// `drift_mm`. The state is predicted to `time_s` first (a time before the last update
    /// counts as the same time). Measurements that are not finite or name no component are
    /// ignored. Returns how many were used.
    pub fn update(&mut self, time_s: f64, measurements: &[(usize, [f64; 3], f64)]) -> usize {
        let dt_s = self.updated_s.map_or(0.0, |t| (time_s - t).max(0.0));
        for k in 0..3 {
            let (f, q) = self.transition(k, dt_s);
            self.state[k] = f * self.state[k];
            self.cov[k] = f * self.cov[k] * f.transpose() + q;
        }
        self.updated_s = Some(self.updated_s.map_or(time_s, |t| t.max(time_s)));
        let mut used = 0;
        for &(k, at_mm, y) in measurements {
            if k > 2 || !y.is_finite() || at_mm.iter().any(|v| !v.is_finite()) {
                continue;
            }
            let h = State::from([
                1.0,
                at_mm[0] - self.centre_mm[0],
                at_mm[1] - self.centre_mm[1],
                at_mm[2] - self.centre_mm[2],
                0.0,
            ]);
            let ph = self.cov[k] * h;
            let s = h.dot(&ph) + self.measurement_mm2[k];
            let gain = ph / s;
            let innovation = y - h.dot(&self.state[k]);
            self.state[k] += gain * innovation;
            self.cov[k] -= gain * ph.transpose();
            used += 1;
        }
        used
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::rngs::StdRng;
    use rand::SeedableRng;
    use rand_distr::{Distribution, Normal};

    fn settings() -> FieldSettings {
        FieldSettings {
            walk_offset_um_per_sqrt_h: 0.5,
            walk_gradient_um_per_m_sqrt_h: 0.5,
            measurement_sigma_um: 0.3,
            initial_offset_um: 10.0,
            initial_gradient_um_per_m: 20.0,
            rate_sigma_um_per_min: 1e-9,
            rate_tau_s: 120.0,
        }
    }

    /// Four artefacts, not in one plane.
    const AT: [[f64; 3]; 4] = [
        [40.0, 40.0, -380.0],
        [520.0, 40.0, -380.0],
        [40.0, 360.0, -380.0],
        [280.0, 200.0, -130.0],
    ];

    #[test]
    fn a_linear_drift_probed_at_four_places_is_recovered_over_the_whole_volume() {
        let centre = [220.0, 160.0, -317.5];
        let mut f = DriftField::new(centre, &settings()).unwrap();
        // Truth: offsets of a few µm, gradients of 5–10 µm/m.
        let truth = |q: [f64; 3]| {
            [
                0.002 + 8e-6 * (q[2] - centre[2]),
                -0.001 + 5e-6 * (q[0] - centre[0]),
                0.003 - 10e-6 * (q[2] - centre[2]) + 4e-6 * (q[1] - centre[1]),
            ]
        };
        let mut rng = StdRng::seed_from_u64(5);
        let noise = Normal::new(0.0, 0.3e-3).unwrap();
        for cycle in 0..6 {
            let m: Vec<(usize, [f64; 3], f64)> = AT
                .iter()
                .flat_map(|&p| (0..3).map(move |k| (k, p, truth(p)[k])))
                .map(|(k, p, y)| (k, p, y + noise.sample(&mut rng)))
                .collect();
            assert_eq!(f.update(cycle as f64 * 1800.0, &m), 12);
        }
        // At a corner none of the artefacts is at, within a fraction of a µm.
        for q in [
            [540.0, 380.0, -30.0],
            [20.0, 20.0, -430.0],
            [540.0, 20.0, -30.0],
        ] {
            let (est, tru) = (f.drift_at_mm(q), truth(q));
            for k in 0..3 {
                assert!(
                    (est[k] - tru[k]).abs() < 0.4e-3,
                    "component {k} at {q:?}: {} against {}",
                    est[k],
                    tru[k]
                );
            }
        }
    }

    #[test]
    fn artefacts_at_one_height_leave_the_z_gradient_at_its_prior_of_zero() {
        let mut f = DriftField::new([280.0, 200.0, -380.0], &settings()).unwrap();
        let m: Vec<_> = AT[..3]
            .iter()
            .map(|&p| (0usize, p, 0.002 + 1e-5 * (p[0] - 280.0)))
            .collect();
        f.update(0.0, &m);
        let g = f.gradient(0);
        assert!((g[0] - 1e-5).abs() < 1e-6, "x gradient {g:?}");
        assert!(g[2].abs() < 1e-9, "z gradient seen by no artefact: {g:?}");
    }

    /// Settings of an offset-only field (every gradient held at 0) that single gradient terms
    /// are opened in with [`DriftField::set_gradient_prior`].
    fn offset_only() -> FieldSettings {
        FieldSettings {
            walk_offset_um_per_sqrt_h: 1.0,
            walk_gradient_um_per_m_sqrt_h: 1e-9,
            measurement_sigma_um: 0.45,
            initial_offset_um: 2.0,
            initial_gradient_um_per_m: 1e-9,
            rate_sigma_um_per_min: 1e-9,
            rate_tau_s: 120.0,
        }
    }

    /// Ex of spheres at both ends of X, `cycles` hourly cycles of two touches per sphere with
    /// noise σ 0.45 µm, truth `offset + gradient · (x − centre)`: the estimated Ex gradient
    /// along X (µm/m) with the term opened, and the raw least-squares gradient of the last
    /// cycle's readings (µm/m, the slope between the spheres' means: a gradient measured anew
    /// each cycle).
    fn ex_along_x(seed: u64, gradient_um_per_m: f64, cycles: usize) -> (f64, f64) {
        let centre = [280.0, 200.0, -317.5];
        let mut f = DriftField::new(centre, &offset_only()).unwrap();
        f.set_gradient_prior(0, 0, 3.0, 0.5).unwrap();
        let mut rng = StdRng::seed_from_u64(seed);
        let noise = Normal::new(0.0, 0.45e-3).unwrap();
        let mut raw = 0.0;
        for cycle in 0..cycles {
            let m: Vec<(usize, [f64; 3], f64)> = [AT[0], AT[0], AT[1], AT[1]]
                .iter()
                .map(|&p| {
                    let y = 1.5e-3 + gradient_um_per_m * 1e-6 * (p[0] - centre[0]);
                    (0, p, y + noise.sample(&mut rng))
                })
                .collect();
            raw = 0.5 * (m[2].2 + m[3].2 - m[0].2 - m[1].2) / (AT[1][0] - AT[0][0]) * 1e6;
            assert_eq!(f.update(cycle as f64 * 3600.0, &m), 4);
        }
        (f.gradient(0)[0] * 1e6, raw)
    }

    #[test]
    fn a_gradient_term_with_its_prior_recovers_a_known_gradient_from_noisy_probe_readings() {
        // 4 µm/m of Ex along X (an X scale the model misses), six hourly cycles.
        let errs: Vec<f64> = (0..20)
            .map(|seed| ex_along_x(seed, 4.0, 6).0 - 4.0)
            .collect();
        let mean = errs.iter().sum::<f64>() / 20.0;
        let rms = (errs.iter().map(|e| e * e).sum::<f64>() / 20.0).sqrt();
        // The prior (σ 3 µm/m) pulls a little toward 0; the noise leaves well under 1 µm/m.
        assert!(mean.abs() < 0.6, "bias {mean} µm/m");
        assert!(rms < 1.0, "rms error {rms} µm/m");
        // The other terms and components stay at their prior of 0.
        let mut f = DriftField::new([280.0, 200.0, -317.5], &offset_only()).unwrap();
        f.set_gradient_prior(0, 0, 3.0, 0.5).unwrap();
        f.update(0.0, &[(0, AT[1], 2e-3), (0, AT[0], 0.0), (2, AT[3], 1e-3)]);
        assert!(f.gradient(0)[0] > 1e-6, "{:?}", f.gradient(0));
        assert!(f.gradient(0)[1..].iter().all(|g| g.abs() < 1e-12));
        assert!(f.gradient(2).iter().all(|g| g.abs() < 1e-12));
    }

    #[test]
    fn noise_alone_leaves_the_gradient_term_smaller_than_a_raw_least_squares_gradient() {
        // No gradient at all: what the term shows after six hourly cycles is noise, averaged
        // over the cycles (its walk is slow) and shrunk by its prior; a gradient measured anew
        // each cycle (about 0.94 µm/m σ here) shows all of the last cycle's noise.
        let (est, raw): (Vec<f64>, Vec<f64>) = (0..40).map(|seed| ex_along_x(seed, 0.0, 6)).unzip();
        let rms = |v: &[f64]| (v.iter().map(|e| e * e).sum::<f64>() / v.len() as f64).sqrt();
        assert!(
            rms(&est) < 0.7 * rms(&raw),
            "{} against raw {}",
            rms(&est),
            rms(&raw)
        );
        assert!(rms(&est) < 0.7, "{} µm/m from noise alone", rms(&est));
    }

    #[test]
    fn a_gradient_prior_for_no_such_component_or_a_bad_value_is_refused() {
        let mut f = DriftField::new([0.0; 3], &offset_only()).unwrap();
        assert_eq!(
            f.set_gradient_prior(3, 0, 1.0, 1.0).unwrap_err().field,
            "component"
        );
        assert_eq!(
            f.set_gradient_prior(0, 3, 1.0, 1.0).unwrap_err().field,
            "axis"
        );
        let err = f.set_gradient_prior(0, 0, f64::NAN, 1.0).unwrap_err();
        assert_eq!(err.field, "initial_gradient_um_per_m");
        let err = f.set_gradient_prior(0, 0, 1.0, 0.0).unwrap_err();
        assert_eq!(err.field, "walk_gradient_um_per_m_sqrt_h");
    }

    #[test]
    fn bad_settings_and_measurements_are_refused_or_ignored() {
        let bad = FieldSettings {
            walk_gradient_um_per_m_sqrt_h: -1.0,
            ..settings()
        };
        let err = DriftField::new([0.0; 3], &bad).unwrap_err();
        assert_eq!(err.field, "walk_gradient_um_per_m_sqrt_h");
        assert!(DriftField::new([f64::NAN, 0.0, 0.0], &settings()).is_err());
        let mut f = DriftField::new([0.0; 3], &settings()).unwrap();
        let used = f.update(0.0, &[(3, [0.0; 3], 0.001), (0, [0.0; 3], f64::NAN)]);
        assert_eq!(used, 0);
        assert_eq!(f.drift_at_mm([100.0, 0.0, 0.0]), [0.0; 3]);
    }

    #[test]
    fn a_rate_seen_within_a_cycle_carries_the_offset_on_and_then_fades() {
        let s = FieldSettings {
            rate_sigma_um_per_min: 1.0,
            rate_tau_s: 100.0,
            measurement_sigma_um: 0.05,
            ..settings()
        };
        let mut f = DriftField::new([0.0; 3], &s).unwrap();
        // Ez drift rising at 0.5 µm/min, measured at 0, 60, 120 s.
        for k in 0..3 {
            let t = 60.0 * k as f64;
            f.update(t, &[(2, [0.0; 3], 0.5e-3 * t / 60.0)]);
        }
        let at = |f: &mut DriftField, t: f64| {
            f.observe_time(t);
            f.drift_at_mm([0.0; 3])[2] * 1e3
        };
        let now = at(&mut f, 120.0);
        let later = at(&mut f, 180.0);
        let much_later = at(&mut f, 7200.0);
        assert!(later > now + 0.1, "{now} then {later}");
        // It fades: an hour on it has moved by at most rate × τ.
        assert!(
            much_later - now < 0.5e-3 / 60.0 * 100.0 * 1e3 * 1.5,
            "{much_later}"
        );
        assert!((much_later - at(&mut f, 3600.0)).abs() < 1e-3);
    }
}
