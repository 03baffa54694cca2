//! Accuracy metrics.
//!
//! For a measured series `y` and a prediction `ŷ` of equal length `n`, the residual is
//! `e = y − ŷ`. All metrics carry the unit of the series they are computed on (the twin reports
//! errors in µm, so MAD, RMSE, max |e| and RMS are then µm); MAPE and R² are dimensionless.
//!
//! - MAD  = (1/n) Σ |eᵢ|  (mean absolute deviation of the prediction from the measurement)
//! - MAPE = (Σ |eᵢ|) / (Σ |yᵢ|) = mean|e| / mean|y|, as a **fraction** (0.05 = 5 %).
//!   The textbook MAPE `(1/n) Σ |eᵢ/yᵢ|` explodes wherever the measured error crosses zero,
//!   which geometric errors do all the time; normalising by the mean magnitude is the robust
//!   definition the reports use. When `Σ |yᵢ| = 0` it is undefined and reported as `None`.
//! - RMSE = √((1/n) Σ eᵢ²)
//! - R²   = 1 − SS_res / SS_tot with SS_res = Σ eᵢ², SS_tot = Σ (yᵢ − ȳ)². When the measured
//!   series is constant (SS_tot = 0) R² is undefined and reported as `None` (no invented number).
//! - max |e| = maxᵢ |eᵢ|
//! - RMS(s) = √((1/n) Σ sᵢ²) of any series.
//! - reduction = 1 − RMS(after) / RMS(before), and likewise for max |·|:
//!   1 means everything was removed, 0 nothing, negative values mean compensation made it worse.
//! - |E| = √(Ex² + Ey² + Ez²) per sample for the volumetric error vector.
//!
//! Every function rejects empty input, length mismatches and non-finite values with a
//! [`MetricsError`] instead of returning NaN.

use serde::{Deserialize, Serialize};
use thiserror::Error;

/// Why a metric could not be computed.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum MetricsError {
    /// Two series that must be compared point by point have different lengths.
    #[error("series lengths differ: {left_name} has {left} samples, {right_name} has {right}")]
    LengthMismatch {
        /// Name of the first series.
        left_name: &'static str,
        /// Length of the first series.
        left: usize,
        /// Name of the second series.
        right_name: &'static str,
        /// Length of the second series.
        right: usize,
    },
    /// A series has no samples.
    #[error("the {series} series is empty")]
    Empty {
        /// Name of the empty series.
        series: &'static str,
    },
    /// A series holds NaN or ±∞.
    #[error("the {series} series has a non-finite value ({value}) at index {index}")]
    NonFinite {
        /// Name of the offending series.
        series: &'static str,
        /// Index of the first non-finite value.
        index: usize,
        /// The value itself.
        value: f64,
    },
    /// A reduction relative to a zero baseline is undefined.
    #[error("reduction undefined: the 'before' {what} is zero")]
    ZeroBaseline {
        /// Which baseline was zero (`"RMS"` or `"max |e|"`).
        what: &'static str,
    },
}

/// Accuracy of a prediction against a measured series (see the module doc for the formulas).
///
/// Lengths carry the unit of the input series (µm throughout the twin's reports).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Metrics {
    /// Number of samples.
    pub n: usize,
    /// Mean absolute residual, mean |y − ŷ| (unit of the series).
    pub mad: f64,
    /// Robust MAPE = mean|e| / mean|y| as a fraction (0.05 = 5 %); `None` when mean|y| = 0.
    pub mape: Option<f64>,
    /// Root mean square residual (unit of the series).
    pub rmse: f64,
    /// Coefficient of determination 1 − SS_res/SS_tot; `None` when the measured series is constant.
    pub r2: Option<f64>,
    /// Largest absolute residual (unit of the series).
    pub max_abs_err: f64,
    /// Mean residual mean(y − ŷ), the bias of the prediction (unit of the series).
    pub mean_err: f64,
    /// RMS of the measured series itself (unit of the series).
    pub rms_measured: f64,
}

impl Metrics {
    /// Computes all metrics of `predicted` against `measured` (point by point).
    pub fn of(measured: &[f64], predicted: &[f64]) -> Result<Self, MetricsError> {
        check_series("measured", measured)?;
        check_series("predicted", predicted)?;
        check_same_len("measured", measured, "predicted", predicted)?;
        let n_f = measured.len() as f64;
        let mean_y = measured.iter().sum::<f64>() / n_f;
        let (mut sum_abs_e, mut sum_abs_y, mut ss_res, mut ss_tot, mut sum_e, mut ss_y) =
            (0.0, 0.0, 0.0, 0.0, 0.0, 0.0);
        let mut max_abs_err: f64 = 0.0;
        for (&y, &yhat) in measured.iter().zip(predicted) {
            let e = y - yhat;
            sum_abs_e += e.abs();
            sum_abs_y += y.abs();
            ss_res += e * e;
            ss_tot += (y - mean_y) * (y - mean_y);
            sum_e += e;
            ss_y += y * y;
            max_abs_err = max_abs_err.max(e.abs());
        }
        Ok(Self {
            n: measured.len(),
            mad: sum_abs_e / n_f,
            mape: (sum_abs_y > 0.0).then(|| sum_abs_e / sum_abs_y),
            rmse: (ss_res / n_f).sqrt(),
            r2: (ss_tot > 0.0).then(|| 1.0 - ss_res / ss_tot),
            max_abs_err,
            mean_err: sum_e / n_f,
            rms_measured: (ss_y / n_f).sqrt(),
        })
    }
}

/// How much of an error a compensation removed (see the module doc).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Reduction {
    /// 1 − RMS(after)/RMS(before), dimensionless (1 = all removed).
    pub rms: f64,
    /// 1 − max|after| / max|before|, dimensionless.
    pub max: f64,
    /// RMS of the error before compensation (unit of the series).
    pub rms_before: f64,
    /// RMS of the error after compensation (unit of the series).
    pub rms_after: f64,
    /// Largest |error| before compensation (unit of the series).
    pub max_before: f64,
    /// Largest |error| after compensation (unit of the series).
    pub max_after: f64,
}

impl Reduction {
    /// Compares the error series of the same program run before and after compensation.
    ///
    /// Both series must have the same length (they are the same points of the same program).
    pub fn of(before: &[f64], after: &[f64]) -> Result<Self, MetricsError> {
        check_same_len("before", before, "after", after)?;
        let rms_before = rms_named("before", before)?;
        let rms_after = rms_named("after", after)?;
        let max_before = max_abs_named("before", before)?;
        let max_after = max_abs_named("after", after)?;
        if rms_before == 0.0 {
            return Err(MetricsError::ZeroBaseline { what: "RMS" });
        }
        // max_before = 0 implies rms_before = 0, so it is non-zero here.
        Ok(Self {
            rms: 1.0 - rms_after / rms_before,
            max: 1.0 - max_after / max_before,
            rms_before,
            rms_after,
            max_before,
            max_after,
        })
    }
}

/// Root mean square √(mean sᵢ²) of a series (unit of the series).
pub fn rms(series: &[f64]) -> Result<f64, MetricsError> {
    rms_named("input", series)
}

/// Largest absolute value of a series (unit of the series).
pub fn max_abs(series: &[f64]) -> Result<f64, MetricsError> {
    max_abs_named("input", series)
}

/// Residuals e = y − ŷ, point by point.
pub fn residuals(measured: &[f64], predicted: &[f64]) -> Result<Vec<f64>, MetricsError> {
    check_series("measured", measured)?;
    check_series("predicted", predicted)?;
    check_same_len("measured", measured, "predicted", predicted)?;
    Ok(measured.iter().zip(predicted).map(|(y, p)| y - p).collect())
}

/// Euclidean norm |E| = √(Ex² + Ey² + Ez²) of one error vector (unit of the components).
pub fn norm3(e: [f64; 3]) -> f64 {
    (e[0] * e[0] + e[1] * e[1] + e[2] * e[2]).sqrt()
}

/// |E| per sample from the three component series (unit of the components).
pub fn vector_norms(ex: &[f64], ey: &[f64], ez: &[f64]) -> Result<Vec<f64>, MetricsError> {
    check_series("ex", ex)?;
    check_series("ey", ey)?;
    check_series("ez", ez)?;
    check_same_len("ex", ex, "ey", ey)?;
    check_same_len("ex", ex, "ez", ez)?;
    Ok(ex
        .iter()
        .zip(ey)
        .zip(ez)
        .map(|((&x, &y), &z)| norm3([x, y, z]))
        .collect())
}

fn rms_named(name: &'static str, series: &[f64]) -> Result<f64, MetricsError> {
    check_series(name, series)?;
    let ss: f64 = series.iter().map(|s| s * s).sum();
    Ok((ss / series.len() as f64).sqrt())
}

fn max_abs_named(name: &'static str, series: &[f64]) -> Result<f64, MetricsError> {
    check_series(name, series)?;
    Ok(series.iter().fold(0.0_f64, |m, s| m.max(s.abs())))
}

fn check_series(series: &'static str, values: &[f64]) -> Result<(), MetricsError> {
    if values.is_empty() {
        return Err(MetricsError::Empty { series });
    }
    match values.iter().position(|v| !v.is_finite()) {
        Some(index) => Err(MetricsError::NonFinite {
            series,
            index,
            value: values[index],
        }),
        None => Ok(()),
    }
}

fn check_same_len(
    left_name: &'static str,
    left: &[f64],
    right_name: &'static str,
    right: &[f64],
) -> Result<(), MetricsError> {
    if left.len() == right.len() {
        Ok(())
    } else {
        Err(MetricsError::LengthMismatch {
            left_name,
            left: left.len(),
            right_name,
            right: right.len(),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Metrics are sums of a handful of exact-ish decimals: 1e-12 (a femtometre in µm) is tight.
    const TOL: f64 = 1e-12;

    fn close(a: f64, b: f64) -> bool {
        (a - b).abs() <= TOL
    }

    #[test]
    fn metrics_of_a_four_point_series_match_hand_computation() {
        // y = [1, 2, 3, 4], ŷ = [1, 3, 2, 4] → e = [0, −1, 1, 0]
        // MAD = 2/4 = 0.5; Σ|y| = 10 → MAPE = 2/10 = 0.2; RMSE = √(2/4) = √0.5
        // ȳ = 2.5, SS_tot = 2.25+0.25+0.25+2.25 = 5, SS_res = 2 → R² = 1 − 2/5 = 0.6
        // max|e| = 1, mean e = 0, RMS(y) = √(30/4) = √7.5
        let m = Metrics::of(&[1.0, 2.0, 3.0, 4.0], &[1.0, 3.0, 2.0, 4.0]).unwrap();
        assert_eq!(m.n, 4);
        assert!(close(m.mad, 0.5));
        assert!(close(m.mape.unwrap(), 0.2));
        assert!(close(m.rmse, 0.5_f64.sqrt()));
        assert!(close(m.r2.unwrap(), 0.6));
        assert!(close(m.max_abs_err, 1.0));
        assert!(close(m.mean_err, 0.0));
        assert!(close(m.rms_measured, 7.5_f64.sqrt()));
    }

    #[test]
    fn mape_uses_mean_magnitudes_so_a_zero_crossing_series_stays_finite() {
        // y = [−2, 0, 2], ŷ = [−1, 1, 2] → e = [−1, −1, 0]; Σ|e| = 2, Σ|y| = 4 → MAPE = 0.5
        // ȳ = 0, SS_tot = 8, SS_res = 2 → R² = 0.75; mean e = −2/3
        let m = Metrics::of(&[-2.0, 0.0, 2.0], &[-1.0, 1.0, 2.0]).unwrap();
        assert!(close(m.mape.unwrap(), 0.5));
        assert!(close(m.r2.unwrap(), 0.75));
        assert!(close(m.mean_err, -2.0 / 3.0));
        assert!(close(m.mad, 2.0 / 3.0));
    }

    #[test]
    fn r2_is_none_for_a_constant_measured_series_and_mape_none_for_an_all_zero_one() {
        let m = Metrics::of(&[3.0, 3.0], &[3.0, 4.0]).unwrap();
        assert_eq!(m.r2, None);
        assert!(close(m.mape.unwrap(), 1.0 / 6.0));
        let z = Metrics::of(&[0.0, 0.0], &[0.5, -0.5]).unwrap();
        assert_eq!(z.mape, None);
        assert_eq!(z.r2, None);
        assert!(close(z.rmse, 0.5));
    }

    #[test]
    fn a_perfect_prediction_has_zero_error_and_r2_of_one() {
        let y = [1.5, -2.0, 7.25];
        let m = Metrics::of(&y, &y).unwrap();
        assert_eq!((m.mad, m.rmse, m.max_abs_err), (0.0, 0.0, 0.0));
        assert_eq!(m.r2, Some(1.0));
        assert_eq!(m.mape, Some(0.0));
    }

    #[test]
    fn a_prediction_worse_than_the_mean_has_negative_r2() {
        // y = [0, 2], ȳ = 1, SS_tot = 2; ŷ = [2, 0] → SS_res = 8 → R² = 1 − 4 = −3
        let m = Metrics::of(&[0.0, 2.0], &[2.0, 0.0]).unwrap();
        assert!(close(m.r2.unwrap(), -3.0));
    }

    #[test]
    fn bad_inputs_are_errors_not_panics() {
        assert_eq!(
            Metrics::of(&[1.0, 2.0], &[1.0]),
            Err(MetricsError::LengthMismatch {
                left_name: "measured",
                left: 2,
                right_name: "predicted",
                right: 1
            })
        );
        assert_eq!(
            Metrics::of(&[], &[]),
            Err(MetricsError::Empty { series: "measured" })
        );
        assert!(matches!(
            Metrics::of(&[1.0, f64::NAN], &[1.0, 2.0]),
            Err(MetricsError::NonFinite {
                series: "measured",
                index: 1,
                ..
            })
        ));
        assert!(matches!(
            Metrics::of(&[1.0, 2.0], &[f64::INFINITY, 2.0]),
            Err(MetricsError::NonFinite {
                series: "predicted",
                index: 0,
                ..
            })
        ));
        assert_eq!(rms(&[]), Err(MetricsError::Empty { series: "input" }));
        assert!(max_abs(&[f64::NEG_INFINITY]).is_err());
        assert!(residuals(&[1.0], &[1.0, 2.0]).is_err());
        assert!(vector_norms(&[1.0], &[1.0], &[1.0, 2.0]).is_err());
    }

    #[test]
    fn rms_and_max_abs_of_a_series_match_hand_computation() {
        // [3, −4] → RMS = √((9 + 16)/2) = √12.5; max |·| = 4
        assert!(close(rms(&[3.0, -4.0]).unwrap(), 12.5_f64.sqrt()));
        assert!(close(max_abs(&[3.0, -4.0]).unwrap(), 4.0));
        assert_eq!(
            residuals(&[5.0, 1.0], &[2.0, 3.0]).unwrap(),
            vec![3.0, -2.0]
        );
    }

    #[test]
    fn reduction_of_an_error_cut_to_a_fifth_is_eighty_percent() {
        // before = [10, −10, 5]: RMS = √(225/3) = √75, max 10
        // after  = [2, −2, 1]:   RMS = √(9/3)  = √3,  max 2 → both reductions 1 − 1/5 = 0.8
        let r = Reduction::of(&[10.0, -10.0, 5.0], &[2.0, -2.0, 1.0]).unwrap();
        assert!(close(r.rms, 0.8));
        assert!(close(r.max, 0.8));
        assert!(close(r.rms_before, 75.0_f64.sqrt()));
        assert!(close(r.max_after, 2.0));
    }

    #[test]
    fn reduction_is_negative_when_compensation_makes_it_worse_and_an_error_for_zero_baseline() {
        // before = [1, 1] (RMS 1, max 1), after = [2, 0] (RMS √2, max 2)
        let r = Reduction::of(&[1.0, 1.0], &[2.0, 0.0]).unwrap();
        assert!(close(r.rms, 1.0 - 2.0_f64.sqrt()));
        assert!(close(r.max, -1.0));
        assert_eq!(
            Reduction::of(&[0.0, 0.0], &[1.0, 0.0]),
            Err(MetricsError::ZeroBaseline { what: "RMS" })
        );
        assert!(Reduction::of(&[1.0], &[1.0, 2.0]).is_err());
    }

    #[test]
    fn vector_norm_of_a_3_4_12_error_is_13() {
        assert!(close(norm3([3.0, 4.0, 12.0]), 13.0));
        let n = vector_norms(&[3.0, 0.0], &[4.0, -2.0], &[12.0, 0.0]).unwrap();
        assert!(close(n[0], 13.0) && close(n[1], 2.0));
    }

    #[test]
    fn metrics_survive_a_json_round_trip() {
        let m = Metrics::of(&[0.0, 0.0], &[0.5, -0.5]).unwrap();
        let back: Metrics = serde_json::from_str(&serde_json::to_string(&m).unwrap()).unwrap();
        assert_eq!(m, back);
    }
}
