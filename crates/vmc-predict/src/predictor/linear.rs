//! The linear-regression baseline: each component of E as a linear model of
//! `[1, x, y, z, x², y², z², xy, xz, yz, ΔT_i, ΔT_i·x, ΔT_i·y, ΔT_i·z]` (model in the
//! `predictor` module doc), trained on `volumetric` records.
//!
//! Positions are normalised, `x = (X − c_X)/h_X` with `c` the centre and `h` the half range of
//! the measured positions, and `ΔT_i = T_i − T̄_i` with `T̄` the mean reading; both are computed
//! over all `volumetric` records. They are a pure reparametrisation: shifting `T̄` or rescaling
//! `x` maps the span of the features onto itself, so they change the conditioning, not the fit.

use serde::{Deserialize, Serialize};

use crate::dataset::{Dataset, Instrument};
use crate::linreg::LinearModel;
use crate::synthesis::MachineGeometry;

use super::data::{fit_linear, records_of, required_values, CycleSplit, SensorSelection, Table};
use super::kind::{check_linear_model, ModelKind};
use super::volumetric::E_OUTPUTS;
use super::{assert_temps_len, ErrorPredictor, PredictError, Settings, TrainSummary};

/// Number of position-only features (without the intercept).
const N_POS_FEATURES: usize = 9;

/// How raw positions and readings become features.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub(crate) struct FeatureScaling {
    /// Centre of the measured positions, mm.
    pub pos_centre_mm: [f64; 3],
    /// Half range of the measured positions, mm (1 where all positions were equal).
    pub pos_half_range_mm: [f64; 3],
    /// Reference reading of each sensor (mean over the records), °C.
    pub temp_ref_degc: Vec<f64>,
}

/// The trained parts of a linear model; what the model file stores under `"model"`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub(crate) struct LinearParts {
    /// Feature scalings.
    pub scaling: FeatureScaling,
    /// Features → (Ex, Ey, Ez) µm.
    pub regression: LinearModel,
}

/// Linear-regression baseline.
#[derive(Debug, Clone)]
pub struct LinearPredictor {
    sensors: Vec<String>,
    geometry: MachineGeometry,
    parts: LinearParts,
    /// The readings last observed, °C (model sensor order; NaN before the first).
    readings: Vec<f64>,
    /// Feature scratch of a query.
    features: Vec<f64>,
}

/// Number of features for `k` sensors.
fn n_features(k: usize) -> usize {
    N_POS_FEATURES + 4 * k
}

/// Writes the features of `(q, temps)` into `f` (length `n_features(k)`).
fn features_into(p: &FeatureScaling, q_mm: [f64; 3], temps: &[f64], f: &mut [f64]) {
    let x: [f64; 3] =
        std::array::from_fn(|i| (q_mm[i] - p.pos_centre_mm[i]) / p.pos_half_range_mm[i]);
    f[..N_POS_FEATURES].copy_from_slice(&[
        x[0],
        x[1],
        x[2],
        x[0] * x[0],
        x[1] * x[1],
        x[2] * x[2],
        x[0] * x[1],
        x[0] * x[2],
        x[1] * x[2],
    ]);
    let k = temps.len();
    let rest = &mut f[N_POS_FEATURES..];
    for (i, (t, r)) in temps.iter().zip(&p.temp_ref_degc).enumerate() {
        let dt = t - r;
        rest[i] = dt;
        rest[k + i] = dt * x[0];
        rest[2 * k + i] = dt * x[1];
        rest[3 * k + i] = dt * x[2];
    }
}

impl LinearPredictor {
    /// Assembles a predictor, checking the parts against `sensors`.
    pub(crate) fn from_parts(
        sensors: Vec<String>,
        geometry: MachineGeometry,
        parts: LinearParts,
    ) -> Result<Self, PredictError> {
        let k = sensors.len();
        check_linear_model("linear", &parts.regression, n_features(k), 3)?;
        let sc = &parts.scaling;
        let scales_ok = sc
            .pos_half_range_mm
            .iter()
            .all(|h| h.is_finite() && *h > 0.0)
            && sc.pos_centre_mm.iter().all(|c| c.is_finite())
            && sc.temp_ref_degc.len() == k
            && sc.temp_ref_degc.iter().all(|t| t.is_finite());
        if !scales_ok {
            return Err(PredictError::Inconsistent {
                reason: format!(
                    "linear model scalings: need finite centres, positive half ranges and {k} \
                     finite reference temperatures"
                ),
            });
        }
        Ok(Self {
            sensors,
            geometry,
            parts,
            readings: vec![f64::NAN; k],
            features: vec![0.0; n_features(k)],
        })
    }

    /// The machine geometry stored with the model (not used by the prediction).
    pub fn geometry(&self) -> &MachineGeometry {
        &self.geometry
    }

    /// The trained parts (for the model file).
    pub(crate) fn parts(&self) -> &LinearParts {
        &self.parts
    }

    /// Rejects a machine whose sensor names or order differ from the model's.
    ///
    /// # Errors
    /// [`PredictError::SensorMismatch`] listing expected and found names.
    pub fn check_sensors(&self, machine_sensor_names: &[String]) -> Result<(), PredictError> {
        super::check_sensor_names(&self.sensors, machine_sensor_names)
    }
}

impl ErrorPredictor for LinearPredictor {
    fn sensor_names(&self) -> &[String] {
        &self.sensors
    }

    #[inline]
    fn predict_error_mm(&mut self, q_mm: [f64; 3]) -> [f64; 3] {
        features_into(
            &self.parts.scaling,
            q_mm,
            &self.readings,
            &mut self.features,
        );
        let mut e = [0.0; 3];
        // Widths were checked in `from_parts`, so this cannot fail.
        let _ = self.parts.regression.predict_into(&self.features, &mut e);
        [e[0] * 1e-3, e[1] * 1e-3, e[2] * 1e-3]
    }

    fn observe_readings(&mut self, _time_s: f64, temps_degc: &[f64]) {
        assert_temps_len(temps_degc, self.sensors.len());
        self.readings.copy_from_slice(temps_degc);
    }

    /// A baseline of the readings only: the commanded spindle speed is not one of its inputs.
    fn observe_spindle_speed(&mut self, _time_s: f64, _rpm: f64) {}

    /// A baseline of the readings only: the axes' commanded feeds are not among its inputs.
    fn observe_axis_feeds(&mut self, _time_s: f64, _feeds_mm_per_min: [f64; 3]) {}

    fn change_tool(&mut self, tool_offset_mm: [f64; 3]) -> Result<(), PredictError> {
        super::same_tool_only(&self.geometry, tool_offset_mm)
    }
}

/// Trains the linear-regression baseline on the `volumetric` records.
///
/// # Errors
/// No or too few `volumetric` records, an empty cell, sensors not in the dataset, or a
/// regression failure (e.g. collinear features with `linear_ridge = 0`).
pub fn train_linear(
    ds: &Dataset,
    geometry: &MachineGeometry,
    settings: &Settings,
) -> Result<(LinearPredictor, TrainSummary), PredictError> {
    let sel = SensorSelection::new(ds, settings)?;
    let split = CycleSplit::new(ds, settings)?;
    let recs = records_of(
        ds,
        Instrument::Volumetric,
        "the linear regression",
        settings.min_records,
    )?;
    let k = sel.names.len();
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    let mut temp_ref_degc = vec![0.0; k];
    let mut temps = Vec::with_capacity(k);
    for r in &recs {
        for i in 0..3 {
            lo[i] = lo[i].min(r.pos_mm[i]);
            hi[i] = hi[i].max(r.pos_mm[i]);
        }
        temps.clear();
        sel.push_temps(r, &mut temps, false, None);
        temp_ref_degc
            .iter_mut()
            .zip(&temps)
            .for_each(|(m, t)| *m += t);
    }
    temp_ref_degc
        .iter_mut()
        .for_each(|m| *m /= recs.len() as f64);
    let scaling = FeatureScaling {
        pos_centre_mm: std::array::from_fn(|i| 0.5 * (lo[i] + hi[i])),
        pos_half_range_mm: std::array::from_fn(|i| {
            let h = 0.5 * (hi[i] - lo[i]);
            if h > 0.0 {
                h
            } else {
                1.0
            }
        }),
        temp_ref_degc,
    };
    let mut table = Table::new();
    for r in &recs {
        temps.clear();
        sel.push_temps(r, &mut temps, false, None);
        let mut f = vec![0.0; n_features(k)];
        features_into(&scaling, r.pos_mm, &temps, &mut f);
        table.inputs.push(f);
        table
            .targets
            .push(required_values(r, &[0, 1, 2], Instrument::Volumetric)?);
        table.groups.push(split.id(&r.cycle));
    }
    let (regression, summary) =
        fit_linear("linear", &E_OUTPUTS, &table, &split, settings.linear_ridge)?;
    let parts = LinearParts {
        scaling,
        regression,
    };
    let predictor = LinearPredictor::from_parts(sel.names.clone(), *geometry, parts)?;
    Ok((
        predictor,
        TrainSummary {
            kind: ModelKind::Linear,
            sensors: sel.names,
            val_cycles: split.val_names(),
            nets: vec![summary],
        },
    ))
}

#[cfg(test)]
mod tests {
    use super::super::testdata as td;
    use super::*;

    #[test]
    fn linear_baseline_trains_and_removes_most_of_the_error() {
        let ds = td::dataset(&[4.0, 7.0, 5.5, 3.0], 11);
        let (mut p, summary) = train_linear(&ds, &td::geometry(), &Settings::default()).unwrap();
        let pairs: Vec<_> = td::held_out(6.0, 5)
            .into_iter()
            .map(|(q, t, e)| (td::predict_at(&mut p, q, &t), e))
            .collect();
        let (err, truth) = td::rms_um(&pairs);
        // The truth has sin/cos profiles and products of temperatures the features cannot
        // express; a quadratic-in-position model must still remove well over half of it.
        assert!(
            err < 0.5 * truth,
            "{err} µm vs truth {truth} µm\n{summary:#?}"
        );
        assert_eq!(summary.nets[0].hidden_units, None);
    }

    #[test]
    fn features_of_a_known_point_are_hand_computed() {
        let scaling = FeatureScaling {
            pos_centre_mm: [100.0, 0.0, -200.0],
            pos_half_range_mm: [100.0, 50.0, 200.0],
            temp_ref_degc: vec![20.0, 22.0],
        };
        let mut f = vec![0.0; n_features(2)];
        features_into(&scaling, [200.0, -25.0, -300.0], &[21.0, 24.0], &mut f);
        // x = 1, y = −0.5, z = −0.5, ΔT = (1, 2)
        let want = [
            1.0, -0.5, -0.5, 1.0, 0.25, 0.25, -0.5, -0.5, 0.25, 1.0, 2.0, 1.0, 2.0, -0.5, -1.0,
            -0.5, -1.0,
        ];
        assert_eq!(f, want);
    }
}
