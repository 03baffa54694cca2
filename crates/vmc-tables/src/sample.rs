//! Tables from an error model at a stated thermal state, and what they lose against it.
//!
//! **Model.** The predictor answers `E(q)` = actual − nominal tool position (mm, workpiece
//! frame) at axis positions `q` (mm) under the readings it last observed (the thermal state),
//! for a positive approach of every axis; a negative approach of axis `k` shifts `E_k` by the
//! model's reversal `r_k` ([`ErrorPredictor::negative_approach_shift_mm`](vmc_predict::predictor::ErrorPredictor::negative_approach_shift_mm), the same term the
//! live compensator keys on the commanded direction). A table holds *corrections* `c = −E`,
//! the amount a controller adds to an axis command (first order: the correction at the
//! commanded position; the exact inverse `c = −E(p + c)` differs by `|∂E/∂q|·|E|` ≈ 1e-5 ×
//! 50 µm = 0.5 nm, below the tables' 1 nm resolution).
//!
//! **Sampling.** Axis `k` is sampled on a grid of its travel (`points` from the [`Spacing`],
//! `step = (max − min)/(points − 1)`, both on the 1 nm grid), the other axes at the reference
//! position `q_ref` (default: the middle of each travel):
//!
//! - own-axis table of `k` (what a per-joint table can carry):
//!   forward `c_k(x) = −E_k(q_ref with q_k = x)`, reverse `c_k(x) − r_k`;
//! - cross table of output `j` along input `k ≠ j` (what only a cross table can carry):
//!   `c_jk(x) = −(E_j(q_ref with q_k = x) − E_j(q_ref))`. The reference value is taken out so
//!   that the tables of one output axis add up: along each axis line through `q_ref`,
//!   `c_jj + Σ_k c_jk = −E_j` exactly at the points.
//!
//! **What the tables lose.** Each table is checked against the model along its line, at
//! `check_subdivisions` points per interval ([`InterpolationCheck`]: the largest difference
//! between the linearly interpolated, 1 nm-quantised table and the model). The whole set is
//! checked over the working volume ([`VolumeCheck`], a grid of `volume_points_per_axis`³
//! points, positive approach): the residual `E + c` once with the own-axis tables alone (a
//! LinuxCNC per-joint configuration) and once with the cross tables added (a CEC
//! configuration). What remains is what no sum of one-axis tables can represent (errors that
//! depend on two positions at once, e.g. an angular error times an Abbe arm) plus the
//! interpolation error.

use serde::{Deserialize, Serialize};
use thiserror::Error;

use crate::linuxcnc::MAX_COMP_POINTS;
use crate::number::{interpolate, quantise_mm, Direction, MAX_ABS_MM};

/// The axes' names, in the model's order.
pub const AXIS_NAMES: [&str; 3] = ["X", "Y", "Z"];

/// Smallest spacing of table points, mm (1 µm): below it the 1 nm grid would distort the
/// positions, and no error profile needs it.
pub const MIN_STEP_MM: f64 = 1e-3;

/// An axis's travel, mm.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct AxisTravel {
    /// Lowest position, mm.
    pub min_mm: f64,
    /// Highest position, mm.
    pub max_mm: f64,
}

/// How many points a table gets along its axis.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub enum Spacing {
    /// Exactly this many points over the travel.
    Points(usize),
    /// The fewest points whose spacing is at most this, mm (default: 10 mm, a quarter of the
    /// laser calibration's 40 mm step, so that a smooth model's curvature is followed to
    /// well under a micrometre; the interpolation check reports what remains).
    MaxStepMm(f64),
}

impl Default for Spacing {
    fn default() -> Self {
        Spacing::MaxStepMm(10.0)
    }
}

/// What to sample. Defaults in [`SamplingSpec::new`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SamplingSpec {
    /// Travel of X, Y, Z, mm.
    pub travel: [AxisTravel; 3],
    /// Position of the axes not being sampled, mm (default: the middle of each travel).
    pub reference_mm: [f64; 3],
    /// Points per table (default: [`Spacing::MaxStepMm`] 10 mm).
    pub spacing: Spacing,
    /// Check points per table interval for the interpolation check (default: 16, even, so the
    /// middle of each interval, where a curvature's interpolation error peaks, is checked).
    pub check_subdivisions: usize,
    /// Grid points per axis of the volume check (default: 9, i.e. 729 points).
    pub volume_points_per_axis: usize,
}

impl SamplingSpec {
    /// The defaults for these travels.
    pub fn new(travel: [AxisTravel; 3]) -> Self {
        Self {
            travel,
            reference_mm: travel.map(|t| 0.5 * (t.min_mm + t.max_mm)),
            spacing: Spacing::default(),
            check_subdivisions: 16,
            volume_points_per_axis: 9,
        }
    }
}

/// Problems with a sampling request or with the model's answers.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum SampleError {
    /// A travel that is not an interval.
    #[error("{axis} travel {min_mm} … {max_mm} mm is not an interval (finite, min < max, within ±1e5 mm)")]
    BadTravel {
        /// The axis.
        axis: &'static str,
        /// Lowest position, mm.
        min_mm: f64,
        /// Highest position, mm.
        max_mm: f64,
    },
    /// A reference position outside its travel.
    #[error("the {axis} reference position {reference_mm} mm is outside the travel {min_mm} … {max_mm} mm")]
    ReferenceOutsideTravel {
        /// The axis.
        axis: &'static str,
        /// The reference, mm.
        reference_mm: f64,
        /// Lowest position, mm.
        min_mm: f64,
        /// Highest position, mm.
        max_mm: f64,
    },
    /// A point count outside what the tables hold.
    #[error(
        "{axis}: {points} points over {travel_mm} mm; the tables take 2 to {max} (LinuxCNC's \
         limit), e.g. a step of at least {min_step_mm:.3} mm"
    )]
    PointCount {
        /// The axis.
        axis: &'static str,
        /// Points asked for.
        points: usize,
        /// The largest count.
        max: usize,
        /// The axis's travel, mm.
        travel_mm: f64,
        /// The smallest step that fits, mm.
        min_step_mm: f64,
    },
    /// Points closer than [`MIN_STEP_MM`].
    #[error("{axis}: a step of {step_mm} mm is below {min_mm} mm")]
    StepTooSmall {
        /// The axis.
        axis: &'static str,
        /// The step, mm.
        step_mm: f64,
        /// The limit, mm.
        min_mm: f64,
    },
    /// A setting outside its range.
    #[error("invalid setting `{field}`: {reason}")]
    BadSetting {
        /// The setting.
        field: &'static str,
        /// What is wrong.
        reason: String,
    },
    /// The model gave no finite error.
    #[error(
        "the model predicts no finite error at {q_mm:?} mm (got {e_mm:?}): has it observed the \
         sensor readings of the thermal state?"
    )]
    NoPrediction {
        /// The axis positions, mm.
        q_mm: [f64; 3],
        /// What the model answered, mm.
        e_mm: [f64; 3],
    },
    /// The model's reversal is not finite.
    #[error("the model's reversal shift {shift_mm:?} mm is not finite")]
    BadReversal {
        /// The shift, mm.
        shift_mm: [f64; 3],
    },
}

/// Equidistant table positions on the 1 nm grid: `start + i·step`, `i < points`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Grid {
    /// First position, mm.
    pub start_mm: f64,
    /// Distance between positions, mm.
    pub step_mm: f64,
    /// Number of positions.
    pub points: usize,
}

impl Grid {
    /// `points` positions over `travel`: `step = (max − min)/(points − 1)` rounded to 1 nm (the
    /// last position is then within `(points − 1)·0.5 nm` of `max`).
    ///
    /// # Errors
    /// A travel that is not an interval, fewer than 2 or more than [`MAX_COMP_POINTS`] points,
    /// a step below [`MIN_STEP_MM`].
    pub fn over(axis: usize, travel: AxisTravel, points: usize) -> Result<Self, SampleError> {
        let name = AXIS_NAMES[axis];
        let span_mm = travel.max_mm - travel.min_mm;
        let usable = |v: f64| v.is_finite() && v.abs() <= MAX_ABS_MM;
        if !(usable(travel.min_mm) && usable(travel.max_mm) && span_mm > 0.0) {
            return Err(SampleError::BadTravel {
                axis: name,
                min_mm: travel.min_mm,
                max_mm: travel.max_mm,
            });
        }
        if !(2..=MAX_COMP_POINTS).contains(&points) {
            return Err(SampleError::PointCount {
                axis: name,
                points,
                max: MAX_COMP_POINTS,
                travel_mm: span_mm,
                min_step_mm: span_mm / (MAX_COMP_POINTS - 1) as f64,
            });
        }
        let step_mm = quantise_mm(span_mm / (points - 1) as f64);
        if step_mm < MIN_STEP_MM {
            return Err(SampleError::StepTooSmall {
                axis: name,
                step_mm,
                min_mm: MIN_STEP_MM,
            });
        }
        Ok(Self {
            start_mm: quantise_mm(travel.min_mm),
            step_mm,
            points,
        })
    }

    /// The grid for `spacing` over `travel` (see [`Spacing`]).
    ///
    /// # Errors
    /// As [`Self::over`]; a maximum step that is not finite and positive.
    pub fn with_spacing(
        axis: usize,
        travel: AxisTravel,
        spacing: Spacing,
    ) -> Result<Self, SampleError> {
        let points = match spacing {
            Spacing::Points(n) => n,
            Spacing::MaxStepMm(s) if s.is_finite() && s > 0.0 => {
                let span = travel.max_mm - travel.min_mm;
                // The 1e-9 keeps an exact division (560 / 10) from gaining a point.
                let intervals = (span / s - 1e-9).ceil().max(1.0);
                if intervals.is_finite() && intervals < 1e6 {
                    intervals as usize + 1
                } else {
                    usize::MAX
                }
            }
            Spacing::MaxStepMm(s) => {
                return Err(SampleError::BadSetting {
                    field: "spacing",
                    reason: format!("a maximum step of {s} mm"),
                })
            }
        };
        Self::over(axis, travel, points)
    }

    /// Position `i`, mm.
    pub fn position_mm(&self, i: usize) -> f64 {
        quantise_mm(self.start_mm + i as f64 * self.step_mm)
    }

    /// All positions, mm.
    pub fn positions_mm(&self) -> Vec<f64> {
        (0..self.points).map(|i| self.position_mm(i)).collect()
    }

    /// The last position, mm.
    pub fn end_mm(&self) -> f64 {
        self.position_mm(self.points - 1)
    }
}

/// How far a table's linear interpolation departs from the model along its line.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct InterpolationCheck {
    /// Largest |table − model correction|, µm.
    pub max_abs_um: f64,
    /// Where along the input axis, mm.
    pub at_mm: f64,
    /// Points compared.
    pub samples: usize,
}

/// The correction of an axis's own error along that axis (a LinuxCNC joint table; a CEC table
/// whose input and output axis are the same).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct OwnAxisTable {
    /// The axis (0 X, 1 Y, 2 Z).
    pub axis: usize,
    /// Its positions.
    pub grid: Grid,
    /// Correction after a positive approach, mm, per position (`−E_k`).
    pub forward_mm: Vec<f64>,
    /// Correction after a negative approach, mm (`−E_k − r_k`).
    pub reverse_mm: Vec<f64>,
    /// The forward column against the model (the reverse one differs by a constant).
    pub check: InterpolationCheck,
}

/// The correction of output axis `output_axis` along input axis `input_axis`, relative to its
/// value at the reference position (a CEC cross table).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CrossTable {
    /// The corrected axis.
    pub output_axis: usize,
    /// The axis whose position is the input.
    pub input_axis: usize,
    /// The input axis's positions.
    pub grid: Grid,
    /// Correction, mm, per position (`−(E_out − E_out(q_ref))`).
    pub correction_mm: Vec<f64>,
    /// Against the model.
    pub check: InterpolationCheck,
}

/// Residual `E + c` of a set of tables over the volume grid, per component X, Y, Z.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct Residual {
    /// Largest |residual|, µm.
    pub max_abs_um: [f64; 3],
    /// RMS residual, µm.
    pub rms_um: [f64; 3],
}

/// What the tables remove of the model's error over the working volume (positive approach).
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct VolumeCheck {
    /// Grid points compared.
    pub points: usize,
    /// Largest |E| of the model itself, µm: what there is to compensate.
    pub model_max_abs_um: [f64; 3],
    /// RMS |E| of the model, µm.
    pub model_rms_um: [f64; 3],
    /// With the own-axis tables only (LinuxCNC per-joint tables).
    pub own_axis_only: Residual,
    /// With the own-axis and the cross tables (CEC).
    pub own_and_cross: Residual,
}

/// Every table of a model at one thermal state.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TableSet {
    /// Reference position of the axes not sampled, mm.
    pub reference_mm: [f64; 3],
    /// The model's error at the reference position, mm.
    pub reference_error_mm: [f64; 3],
    /// The model's reversal `r_k` per axis, mm (reverse − forward correction is `−r_k`).
    pub reversal_shift_mm: [f64; 3],
    /// Own-axis tables of X, Y, Z.
    pub own: Vec<OwnAxisTable>,
    /// Cross tables, every output axis against every other input axis (6).
    pub cross: Vec<CrossTable>,
    /// The whole set against the model over the volume.
    pub volume: VolumeCheck,
}

mod build;

pub use build::sample_tables;

impl TableSet {
    /// The own-axis correction of `axis` at position `x_mm` after an approach in `direction`,
    /// interpolated as a controller does, mm.
    pub fn own_correction_mm(&self, axis: usize, x_mm: f64, direction: Direction) -> f64 {
        let t = &self.own[axis];
        let values = match direction {
            Direction::Positive => &t.forward_mm,
            Direction::Negative => &t.reverse_mm,
        };
        interpolate(&t.grid.positions_mm(), values, x_mm)
    }

    /// The cross correction of `output_axis` at input-axis position `x_mm`, mm (zero when
    /// `output_axis == input_axis`: that is the own-axis table).
    pub fn cross_correction_mm(&self, output_axis: usize, input_axis: usize, x_mm: f64) -> f64 {
        self.cross
            .iter()
            .find(|t| t.output_axis == output_axis && t.input_axis == input_axis)
            .map_or(0.0, |t| {
                interpolate(&t.grid.positions_mm(), &t.correction_mm, x_mm)
            })
    }
}
