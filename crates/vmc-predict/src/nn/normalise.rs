//! Per-feature z-score normalisation `z = (x − mean) / std`, fitted on training data only.

use serde::{Deserialize, Serialize};

use super::samples::DataError;

/// Per-feature affine normalisation, stored in the model so callers work in physical units.
///
/// `mean` and `std` are in the unit of each feature (mm, °C, µm, …). A feature that is constant
/// in the training data gets `std = 1` (it is only centred): dividing by a zero or round-off
/// sized spread would turn noise into huge inputs.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Normaliser {
    /// Mean of each feature over the training data (feature unit).
    pub mean: Vec<f64>,
    /// Population standard deviation of each feature (feature unit), 1 for constant features.
    pub std: Vec<f64>,
}

impl Normaliser {
    /// Fits mean and standard deviation of each of the `width` columns of a row-major buffer.
    pub fn fit(rows: &[f64], width: usize) -> Result<Self, DataError> {
        Self::fit_named(rows, width, "data")
    }

    /// [`Self::fit`], naming the buffer (`"inputs"`, `"targets"`) in a
    /// [`DataError::TooLarge`].
    pub fn fit_named(rows: &[f64], width: usize, what: &'static str) -> Result<Self, DataError> {
        if width == 0 {
            return Err(DataError::ZeroWidth { what: "features" });
        }
        if rows.is_empty() || !rows.len().is_multiple_of(width) {
            return Err(DataError::Shape {
                what: "normaliser data (need at least one whole row)",
                expected: (rows.len() / width).max(1) * width,
                got: rows.len(),
            });
        }
        let n = (rows.len() / width) as f64;
        let mut mean = vec![0.0; width];
        for row in rows.chunks_exact(width) {
            for (m, v) in mean.iter_mut().zip(row) {
                *m += v;
            }
        }
        mean.iter_mut().for_each(|m| *m /= n);
        let mut var = vec![0.0; width];
        for row in rows.chunks_exact(width) {
            for ((s, v), m) in var.iter_mut().zip(row).zip(&mean) {
                *s += (v - m) * (v - m);
            }
        }
        let std = var
            .iter()
            .zip(&mean)
            .map(|(s, m)| {
                let sd = (s / n).sqrt();
                // Relative threshold: a constant column computed in floating point still shows
                // a spread of a few ulps of its mean.
                if sd > 1e-12 * (1.0 + m.abs()) {
                    sd
                } else {
                    1.0
                }
            })
            .collect::<Vec<f64>>();
        if let Some(column) = (0..width).find(|&k| !(mean[k].is_finite() && std[k].is_finite())) {
            return Err(DataError::TooLarge { what, column });
        }
        Ok(Self { mean, std })
    }

    /// The identity normalisation for `width` features (mean 0, std 1).
    pub fn identity(width: usize) -> Self {
        Self {
            mean: vec![0.0; width],
            std: vec![1.0; width],
        }
    }

    /// Number of features.
    pub fn width(&self) -> usize {
        self.mean.len()
    }

    /// Writes `(x − mean) / std` into `z` (both of length `width()`; extra elements are ignored).
    #[inline]
    pub fn normalise_into(&self, x: &[f64], z: &mut [f64]) {
        for (((zi, xi), m), s) in z.iter_mut().zip(x).zip(&self.mean).zip(&self.std) {
            *zi = (xi - m) / s;
        }
    }

    /// Maps normalised values back to physical units in place: `v ← v·std + mean`.
    #[inline]
    pub fn denormalise_in_place(&self, v: &mut [f64]) {
        for ((vi, m), s) in v.iter_mut().zip(&self.mean).zip(&self.std) {
            *vi = *vi * s + m;
        }
    }

    /// True when both vectors have `width` finite entries and every std is positive.
    pub(crate) fn is_valid(&self, width: usize) -> bool {
        self.mean.len() == width
            && self.std.len() == width
            && self.mean.iter().all(|m| m.is_finite())
            && self.std.iter().all(|s| s.is_finite() && *s > 0.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fit_gives_hand_computed_mean_and_std_and_unit_std_for_constant_columns() {
        // column 0: [1, 3] → mean 2, std 1; column 1: [5, 5] → mean 5, constant → std 1
        // column 2: [0, 4] → mean 2, std 2
        let n = Normaliser::fit(&[1.0, 5.0, 0.0, 3.0, 5.0, 4.0], 3).unwrap();
        assert_eq!(n.mean, vec![2.0, 5.0, 2.0]);
        assert_eq!(n.std, vec![1.0, 1.0, 2.0]);
        let mut z = [0.0; 3];
        n.normalise_into(&[3.0, 6.0, 0.0], &mut z);
        assert_eq!(z, [1.0, 1.0, -1.0]);
        n.denormalise_in_place(&mut z);
        assert_eq!(z, [3.0, 6.0, 0.0]);
    }

    #[test]
    fn fit_rejects_empty_or_ragged_data() {
        assert!(Normaliser::fit(&[], 2).is_err());
        assert!(Normaliser::fit(&[1.0, 2.0, 3.0], 2).is_err());
        assert!(Normaliser::fit(&[1.0], 0).is_err());
        // Finite values whose spread overflows are refused with the column, not passed on as
        // an infinite scale.
        assert_eq!(
            Normaliser::fit(&[0.0, 1.0, 1.0, -1.7e308, 2.0, 1.7e308], 2),
            Err(DataError::TooLarge {
                what: "data",
                column: 1
            })
        );
    }
}
