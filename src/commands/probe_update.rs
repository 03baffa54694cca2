//! Drift updates from a program's own probe moves in `vmc-twin run`: a G38 move that touches
//! a setup artefact marked `reference = true` measures what the compensator's model misses,
//! and the measurement updates the compensator's drift estimate online; the moves after it are
//! compensated with the updated drift.
//!
//! **What the controller has** (the information boundary): the latched axis position `q` of
//! the trip (mm, what the program reads in #5061…#5063, in machine coordinates), its own
//! model's prediction `E_pred(q)` at that instant (from the sensor readings and the commanded
//! motion it has followed), and the artefact's nominal geometry from the setup file. The point
//! the controller expects the latch at is the nominal machine's trip point of the same move
//! (the ball meeting the artefact's nominal surface at the probe's pre-travel,
//! `ProbeStation::nominal`) plus half a servo tick of travel at the probe feed (the mean
//! latency). Where the ball really was, `q + E(q)`, is that contact, so
//! `drift = expected − (q + E_pred(q))` (plus the reversal shift of a negative touch) is the
//! part of the error along the touched axis the model misses: the campaign's measurement
//! ([`vmc_predict::drift::artefact_position_mm`], [`ArtefactFix`]), its reference being the
//! setup's geometry instead of a cold qualification cycle. The touch is evaluated with the
//! model alone (without the drift already estimated), as in the campaign.
//!
//! **Estimator**: the campaign's ([`crate::studies::probing::drift_field`]: a Kalman filter of
//! an offset per axis, random walk 1 µm/√h, initial σ 0.7 µm), the measurement σ of one touch
//! ([`crate::studies::probing::touch_sigma_um`]). Only moves along one axis (within 0.1°) are
//! used; an oblique touch is reported, not used.
//!
//! Units: mm for positions, µm for deviations and drifts, s for time.

use serde::Serialize;

use vmc_gcode::interp::{ProbeOutcome, ProbeRequest};
use vmc_machine::touch_probe::{ProbeMove, ProbeStation, TouchProbe};
use vmc_predict::controller::Compensator;
use vmc_predict::drift::{
    artefact_position_mm, ArtefactFix, DriftField, DriftSettingError, LatchedTouch, WithDrift,
};
use vmc_predict::guard::Guarded;
use vmc_predict::predictor::{AnyPredictor, ErrorPredictor};

use crate::studies::probing;

/// A compensating controller whose model carries a probed drift (zero until a reference
/// touch updates it).
pub(super) type DriftCompensator = Guarded<Compensator<WithDrift<AnyPredictor, DriftField>>>;

/// Smallest |direction cosine| of a probe move taken as along one axis (0.1°).
const ALONG_AXIS_COS: f64 = 0.999_998_5;

/// Axis names.
const AXES: [&str; 3] = ["X", "Y", "Z"];

/// One reference touch as the controller evaluated it.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ReferenceTouch {
    /// The touched axis: `X`, `Y` or `Z`.
    pub axis: &'static str,
    /// Where the controller expected the latch along the axis, machine coordinates, mm.
    pub expected_mm: f64,
    /// The latched position along the axis, machine coordinates, mm.
    pub latched_mm: f64,
    /// The model's predicted error along the axis at the latch, µm (with the reversal shift
    /// of a touch in the negative direction; 0 without a model).
    pub model_error_um: f64,
    /// Probed minus expected: `latched + model error − expected`, µm (the drift measured is
    /// its negative).
    pub deviation_um: f64,
    /// Whether the measurement updated the compensator's drift.
    pub applied: bool,
    /// The compensator's drift estimate per axis after this touch, µm (None without a model).
    pub drift_after_um: Option<[f64; 3]>,
}

/// The drift measurement of one touch: the latched point `latched_mm` along `axis` in
/// direction `sign`, the controller expecting it at `expected_mm`, evaluated with `model` as it
/// is now. Returns (the artefact's position along the axis as the model sees it, mm; the drift
/// the model misses, mm). Only controller data enter (module doc).
pub fn drift_of_touch<P: ErrorPredictor>(
    model: &mut P,
    latched_mm: [f64; 3],
    axis: usize,
    sign: f64,
    expected_mm: f64,
) -> Option<(f64, f64)> {
    let touch = LatchedTouch {
        axis_mm: latched_mm,
        axis,
        sign,
    };
    let position = artefact_position_mm(model, &[touch]);
    let mut reference_mm = [None; 3];
    reference_mm[axis] = Some(expected_mm);
    let drift = ArtefactFix { reference_mm }.drift_mm(position)[axis]?;
    Some((position[axis]?, drift))
}

/// The axis a straight move `request` runs along and its direction, if it runs along one.
fn along_axis(request: &ProbeRequest) -> Option<(usize, f64)> {
    let d = [0, 1, 2].map(|a| request.end_mm[a] - request.start_mm[a]);
    let len = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
    if len.is_nan() || len <= 0.0 {
        return None;
    }
    (0..3)
        .find(|&a| d[a].abs() / len >= ALONG_AXIS_COS)
        .map(|a| (a, d[a].signum()))
}

/// The updates of one run: which solids are references and whether to apply them.
pub(super) struct DriftUpdates {
    /// Per solid of the probe station: a reference artefact.
    reference: Vec<bool>,
    /// Update the compensator's drift (false: reported only).
    apply: bool,
    /// The probe (its latency at the move's feed).
    probe: TouchProbe,
}

impl DriftUpdates {
    /// The updates of a run whose probe station's first solids are `artefacts` (in the
    /// setup's order, as `Placement::probe_solids` lists them); applied if `apply`.
    pub fn new(
        artefacts: &[vmc_machine::probe_setup::ArtefactSpec],
        probe: TouchProbe,
        apply: bool,
    ) -> Self {
        Self {
            reference: artefacts.iter().map(|a| a.reference).collect(),
            apply,
            probe,
        }
    }

    /// Whether any artefact is a reference.
    pub fn any_reference(&self) -> bool {
        self.reference.iter().any(|r| *r)
    }

    /// The probe move `request` answered by `answer` at twin time `time_s`: if it tripped on a
    /// reference artefact along one axis, its measurement, applied to `ctrl`'s drift when
    /// updates are on.
    pub fn on_probe(
        &self,
        ctrl: Option<&mut DriftCompensator>,
        station: &ProbeStation,
        request: &ProbeRequest,
        answer: &ProbeMove,
        time_s: f64,
    ) -> Option<ReferenceTouch> {
        let solid = answer.touched?;
        let ProbeOutcome::Tripped { trip_mm, .. } = answer.outcome else {
            return None;
        };
        if !self.reference.get(solid).copied().unwrap_or(false) {
            return None;
        }
        let (axis, sign) = along_axis(request)?;
        let nominal = station.nominal(request);
        let ProbeOutcome::Tripped { trip_mm: nom, .. } = nominal.outcome else {
            return None;
        };
        if nominal.touched != Some(solid) {
            return None;
        }
        // The mean latency: half a servo tick of travel at the move's feed.
        let latency_mm = 0.5 * request.feed_mm_per_min / 60.0 * self.probe.servo_period_s;
        let expected_mm = nom[axis] + sign * latency_mm;
        let (position_mm, drift_mm, drift_after_um, applied) = match ctrl {
            Some(c) => {
                let comp = c.inner_mut().predictor_mut();
                let (position_mm, drift_mm) =
                    drift_of_touch(comp.inner_mut(), trip_mm, axis, sign, expected_mm)?;
                if self.apply {
                    comp.filter_mut()
                        .update(time_s, &[(axis, trip_mm, drift_mm)]);
                }
                let after = comp.filter().offset_mm().map(|v| v * 1e3);
                (position_mm, drift_mm, Some(after), self.apply)
            }
            None => (trip_mm[axis], expected_mm - trip_mm[axis], None, false),
        };
        Some(ReferenceTouch {
            axis: AXES[axis],
            expected_mm,
            latched_mm: trip_mm[axis],
            model_error_um: (position_mm - trip_mm[axis]) * 1e3,
            deviation_um: -drift_mm * 1e3,
            applied,
            drift_after_um,
        })
    }
}

/// The drift field a run's compensator starts with: the campaign's estimator about the
/// reference artefacts' centroid (the machine's home without any), each axis measured with
/// the σ of one touch of `probe`.
///
/// # Errors
/// A probe whose σ is not a usable number.
pub(super) fn run_drift_field(
    artefacts: &[vmc_machine::probe_setup::ArtefactSpec],
    probe: &TouchProbe,
) -> Result<DriftField, DriftSettingError> {
    let centres: Vec<[f64; 3]> = artefacts
        .iter()
        .filter(|a| a.reference)
        .map(|a| a.top_mm.or(a.centre_mm).unwrap_or_default())
        .collect();
    let n = centres.len().max(1) as f64;
    let centre = [0, 1, 2].map(|k| centres.iter().map(|c| c[k]).sum::<f64>() / n);
    let sigma = probing::touch_sigma_um(probe);
    // A probe without scatter: the estimator still needs a measurement σ > 0.
    let sigma = if sigma > 0.0 { sigma } else { 0.01 };
    probing::drift_field(
        &probing::default_field_settings(),
        centre,
        false,
        [Some(sigma); 3],
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A model predicting a fixed error, mm.
    #[derive(Clone)]
    struct Fixed([f64; 3]);

    impl ErrorPredictor for Fixed {
        fn sensor_names(&self) -> &[String] {
            &[]
        }
        fn predict_error_mm(&mut self, _q_mm: [f64; 3]) -> [f64; 3] {
            self.0
        }
        fn negative_approach_shift_mm(&self) -> [f64; 3] {
            [0.0; 3]
        }
        fn observe_readings(&mut self, _time_s: f64, _temps_degc: &[f64]) {}
        fn observe_spindle_speed(&mut self, _time_s: f64, _rpm: f64) {}
        fn observe_axis_feeds(&mut self, _time_s: f64, _feeds: [f64; 3]) {}
    }

    #[test]
    fn a_touch_measures_the_expected_point_minus_the_latch_corrected_by_the_model() {
        // The model predicts Ez = −5 µm; the latch is 3 µm above where the controller expected
        // it: the ball was at latch − 5 µm, so the model misses +2 µm… of error along Z
        // (expected − (latch + E_pred) = −3 + 5 = +2 µm).
        let mut m = Fixed([0.0, 0.0, -0.005]);
        let (position, drift) =
            drift_of_touch(&mut m, [10.0, 20.0, -296.997], 2, -1.0, -297.0).unwrap();
        assert!((position - (-297.002)).abs() < 1e-12);
        assert!((drift - 0.002).abs() < 1e-12);
    }

    #[test]
    fn only_moves_along_one_axis_are_taken_as_touches() {
        let req = |end: [f64; 3]| ProbeRequest {
            end_mm: end,
            ..probe_request()
        };
        assert_eq!(along_axis(&req([0.0, 0.0, -2.0])), Some((2, -1.0)));
        assert_eq!(along_axis(&req([3.0, 0.0, 0.0])), Some((0, 1.0)));
        assert_eq!(along_axis(&req([1.0, 0.0, -2.0])), None);
        assert_eq!(along_axis(&req([0.0, 0.0, 0.0])), None);
    }

    fn probe_request() -> ProbeRequest {
        ProbeRequest {
            line: 1,
            kind: vmc_gcode::interp::ProbeKind {
                toward: true,
                error_on_no_contact: true,
            },
            start_mm: [0.0; 3],
            end_mm: [0.0; 3],
            start_abc_deg: [0.0; 3],
            end_abc_deg: [0.0; 3],
            feed_mm_per_min: 50.0,
        }
    }
}
