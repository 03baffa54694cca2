//! The drift the model misses as a linear field over the working volume, estimated from probed
//! artefacts at several places: per error component `k`, `d_k(q) = b_k + g_k · (q − q₀)` with an
//! offset `b_k` (mm) and a gradient `g_k` (mm per mm) about a centre `q₀` (mm, the artefacts'
//! centroid, fixed when the filter is made).
//!
//! **Why a field.** One artefact sees the residual at one place; the residual of a warm machine
//! varies over the volume (a tilt of the spindle head makes `Ex` change with `Z`, an expansion
//! the model under-predicts makes `Ez` change along an axis), and an offset measured in one
//! corner applied everywhere can double the error in the opposite corner. Artefacts at four
//! places not in one plane determine the whole first-order field.
//!
//! **Estimator**, stated: per component an independent Kalman filter of the state
//! `x_k = [b_k, g_kx, g_ky, g_kz]`, each a random walk (`b` by `walk_offset` µm/√h, each
//! gradient by `walk_gradient` µm per metre per √h), the initial state 0 with σ `initial_offset`
//! µm and `initial_gradient` µm/m. A measurement of component `k` at axis position `p` is
//! `y = b_k + g_k · (p − q₀) + v`, `v ~ N(0, r)`: each scalar measurement is one update with
//! `H = [1, p − q₀]` (taken in turn, which is exact for independent noises). The gradient's
//! prior keeps it near 0 where the artefacts do not see it (all artefacts at one height: no Z
//! gradient).
//!
//! Units: mm, mm/mm and s in the state; µm, µm/m and hours in the settings where the names say so.

use nalgebra::{Matrix4, Vector4};

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
        ] {
            if !(value.is_finite() && value > 0.0) {
                return Err(DriftSettingError { field, value });
            }
        }
        Ok(())
    }
}

/// The offset-and-gradient drift filter (module doc).
#[derive(Debug, Clone, PartialEq)]
pub struct DriftField {
    centre_mm: [f64; 3],
    /// Walk rate per state element, mm² (or (mm/mm)²) per s.
    walk_per_s: Vector4<f64>,
    measurement_mm2: f64,
    state: [Vector4<f64>; 3],
    cov: [Matrix4<f64>; 3],
    updated_s: Option<f64>,
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
        let walk_per_s = Vector4::new(
            mm2(settings.walk_offset_um_per_sqrt_h),
            grad2(settings.walk_gradient_um_per_m_sqrt_h),
            grad2(settings.walk_gradient_um_per_m_sqrt_h),
            grad2(settings.walk_gradient_um_per_m_sqrt_h),
        ) / 3600.0;
        let p0 = Matrix4::from_diagonal(&Vector4::new(
            mm2(settings.initial_offset_um),
            grad2(settings.initial_gradient_um_per_m),
            grad2(settings.initial_gradient_um_per_m),
            grad2(settings.initial_gradient_um_per_m),
        ));
        Ok(DriftField {
            centre_mm,
            walk_per_s,
            measurement_mm2: mm2(settings.measurement_sigma_um),
            state: [Vector4::zeros(); 3],
            cov: [p0; 3],
            updated_s: None,
        })
    }

    /// The estimated drift at axis position `q_mm`, mm per component (what
    /// [`super::WithDrift`] adds to the prediction).
    #[inline]
    pub fn drift_at_mm(&self, q_mm: [f64; 3]) -> [f64; 3] {
        let d = [0, 1, 2].map(|a| q_mm[a] - self.centre_mm[a]);
        self.state
            .map(|x| x[0] + x[1] * d[0] + x[2] * d[1] + x[3] * d[2])
    }

    /// The offset per component, mm (the drift at the centre).
    pub fn offset_mm(&self) -> [f64; 3] {
        self.state.map(|x| x[0])
    }

    /// The gradient of component `k` (0 X, 1 Y, 2 Z) along X, Y, Z, mm per mm.
    pub fn gradient(&self, k: usize) -> [f64; 3] {
        let x = self.state[k.min(2)];
        [x[1], x[2], x[3]]
    }

    /// One probing cycle's measurements at time `time_s` (s): each `(component, at_mm,
    /// drift_mm)` says the drift of that component at axis position `at_mm` was measured as
    /// `drift_mm`. The walk since the last cycle is added first. Measurements that are not
    /// finite or name no component are ignored. Returns how many were used.
    pub fn update(&mut self, time_s: f64, measurements: &[(usize, [f64; 3], f64)]) -> usize {
        let dt_s = self.updated_s.map_or(0.0, |t| (time_s - t).max(0.0));
        let walk = Matrix4::from_diagonal(&(self.walk_per_s * dt_s));
        for p in &mut self.cov {
            *p += walk;
        }
        self.updated_s = Some(time_s);
        let mut used = 0;
        for &(k, at_mm, y) in measurements {
            if k > 2 || !y.is_finite() || at_mm.iter().any(|v| !v.is_finite()) {
                continue;
            }
            let h = Vector4::new(
                1.0,
                at_mm[0] - self.centre_mm[0],
                at_mm[1] - self.centre_mm[1],
                at_mm[2] - self.centre_mm[2],
            );
            let ph = self.cov[k] * h;
            let s = h.dot(&ph) + self.measurement_mm2;
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
}
