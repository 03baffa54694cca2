//! Supervised datasets (input/target rows) and leakage-free train/validation splits.
//!
//! Calibration data are time series: neighbouring samples are nearly identical, so a shuffled
//! split would put near-copies of every validation sample into the training set and make early
//! stopping blind to over-fitting. The splits here therefore keep whole groups (thermal cycles,
//! measurement runs) or whole contiguous blocks together.

use serde::{Deserialize, Serialize};
use thiserror::Error;

/// Why a dataset or a split could not be built.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum DataError {
    /// A width (number of inputs or outputs) of zero.
    #[error("{what} must be at least 1")]
    ZeroWidth {
        /// Which width (`"inputs"`, `"outputs"`).
        what: &'static str,
    },
    /// A buffer length does not match the declared shape.
    #[error("{what}: expected {expected} values, got {got}")]
    Shape {
        /// Which buffer.
        what: &'static str,
        /// Expected number of values.
        expected: usize,
        /// Actual number of values.
        got: usize,
    },
    /// A non-finite value in the data.
    #[error("{what} holds a non-finite value ({value}) at flat index {index}")]
    NonFinite {
        /// Which buffer.
        what: &'static str,
        /// Flat (row-major) index of the first bad value.
        index: usize,
        /// The bad value.
        value: f64,
    },
    /// Values so large that their mean or spread overflows (a unit mistake or a corrupt value).
    #[error("{what}, column {column}: values too large to normalise (their mean or spread overflows); check the data for a unit mistake or a corrupt value")]
    TooLarge {
        /// Which buffer (`"inputs"`, `"targets"`).
        what: &'static str,
        /// 0-based column.
        column: usize,
    },
    /// A split parameter is unusable.
    #[error("invalid split: {reason}")]
    BadSplit {
        /// What is wrong with it.
        reason: &'static str,
    },
}

/// A set of samples: `len` rows of `n_in` inputs and `n_out` targets, stored row-major.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Samples {
    n_in: usize,
    n_out: usize,
    x: Vec<f64>,
    y: Vec<f64>,
}

impl Samples {
    /// Builds a dataset from flat row-major buffers (`x`: len × n_in, `y`: len × n_out).
    pub fn new(n_in: usize, n_out: usize, x: Vec<f64>, y: Vec<f64>) -> Result<Self, DataError> {
        if n_in == 0 {
            return Err(DataError::ZeroWidth { what: "inputs" });
        }
        if n_out == 0 {
            return Err(DataError::ZeroWidth { what: "outputs" });
        }
        if !x.len().is_multiple_of(n_in) {
            return Err(DataError::Shape {
                what: "inputs (not a whole number of rows)",
                expected: x.len() / n_in * n_in,
                got: x.len(),
            });
        }
        let len = x.len() / n_in;
        if y.len() != len * n_out {
            return Err(DataError::Shape {
                what: "targets",
                expected: len * n_out,
                got: y.len(),
            });
        }
        check_finite("inputs", &x)?;
        check_finite("targets", &y)?;
        Ok(Self { n_in, n_out, x, y })
    }

    /// Builds a dataset from one `Vec` per sample (all rows of each side must share a width).
    pub fn from_rows(inputs: &[Vec<f64>], targets: &[Vec<f64>]) -> Result<Self, DataError> {
        if inputs.len() != targets.len() {
            return Err(DataError::Shape {
                what: "target rows",
                expected: inputs.len(),
                got: targets.len(),
            });
        }
        let n_in = inputs.first().map_or(0, Vec::len);
        let n_out = targets.first().map_or(0, Vec::len);
        let mut x = Vec::with_capacity(inputs.len() * n_in);
        let mut y = Vec::with_capacity(targets.len() * n_out);
        for (xi, yi) in inputs.iter().zip(targets) {
            if xi.len() != n_in {
                return Err(DataError::Shape {
                    what: "input row",
                    expected: n_in,
                    got: xi.len(),
                });
            }
            if yi.len() != n_out {
                return Err(DataError::Shape {
                    what: "target row",
                    expected: n_out,
                    got: yi.len(),
                });
            }
            x.extend_from_slice(xi);
            y.extend_from_slice(yi);
        }
        Self::new(n_in.max(1), n_out.max(1), x, y)
    }

    /// Number of samples.
    pub fn len(&self) -> usize {
        self.x.len() / self.n_in
    }

    /// True when there are no samples.
    pub fn is_empty(&self) -> bool {
        self.x.is_empty()
    }

    /// Number of inputs per sample.
    pub fn n_in(&self) -> usize {
        self.n_in
    }

    /// Number of targets per sample.
    pub fn n_out(&self) -> usize {
        self.n_out
    }

    /// Inputs of sample `i` (panics if `i >= len()`, like slice indexing).
    pub fn input(&self, i: usize) -> &[f64] {
        &self.x[i * self.n_in..(i + 1) * self.n_in]
    }

    /// Targets of sample `i` (panics if `i >= len()`, like slice indexing).
    pub fn target(&self, i: usize) -> &[f64] {
        &self.y[i * self.n_out..(i + 1) * self.n_out]
    }

    /// All inputs, row-major.
    pub fn inputs(&self) -> &[f64] {
        &self.x
    }

    /// All targets, row-major.
    pub fn targets(&self) -> &[f64] {
        &self.y
    }

    /// Splits by group id (e.g. thermal cycle): samples whose group is in `val_groups` go to
    /// validation, all others to training. Returns `(train, validation)`.
    pub fn split_by_groups(
        &self,
        groups: &[u64],
        val_groups: &[u64],
    ) -> Result<(Samples, Samples), DataError> {
        if groups.len() != self.len() {
            return Err(DataError::Shape {
                what: "group ids",
                expected: self.len(),
                got: groups.len(),
            });
        }
        let is_val: Vec<bool> = groups.iter().map(|g| val_groups.contains(g)).collect();
        self.split_by_mask(&is_val)
    }

    /// Cuts the samples, in order, into `n_blocks` contiguous blocks of (nearly) equal size and
    /// sends every `val_every`-th block (blocks `val_every − 1`, `2·val_every − 1`, …) to
    /// validation. Returns `(train, validation)`.
    pub fn split_blocks(
        &self,
        n_blocks: usize,
        val_every: usize,
    ) -> Result<(Samples, Samples), DataError> {
        if n_blocks < 2 || n_blocks > self.len() {
            return Err(DataError::BadSplit {
                reason: "need 2 ≤ n_blocks ≤ number of samples",
            });
        }
        if val_every < 2 || val_every > n_blocks {
            return Err(DataError::BadSplit {
                reason: "need 2 ≤ val_every ≤ n_blocks",
            });
        }
        let n = self.len();
        let is_val: Vec<bool> = (0..n)
            .map(|i| (i * n_blocks / n) % val_every == val_every - 1)
            .collect();
        self.split_by_mask(&is_val)
    }

    /// The samples at `indices`, in that order (panics on an out-of-range index).
    pub(crate) fn select(&self, indices: impl Iterator<Item = usize>) -> Samples {
        let mut x = Vec::new();
        let mut y = Vec::new();
        for i in indices {
            x.extend_from_slice(self.input(i));
            y.extend_from_slice(self.target(i));
        }
        Samples {
            n_in: self.n_in,
            n_out: self.n_out,
            x,
            y,
        }
    }

    /// Applies `f_in` to every input row and `f_out` to every target row (used for normalising).
    pub(crate) fn map_rows(
        &self,
        mut f_in: impl FnMut(&[f64], &mut [f64]),
        mut f_out: impl FnMut(&[f64], &mut [f64]),
    ) -> Samples {
        let mut x = vec![0.0; self.x.len()];
        let mut y = vec![0.0; self.y.len()];
        for (src, dst) in self
            .x
            .chunks_exact(self.n_in)
            .zip(x.chunks_exact_mut(self.n_in))
        {
            f_in(src, dst);
        }
        for (src, dst) in self
            .y
            .chunks_exact(self.n_out)
            .zip(y.chunks_exact_mut(self.n_out))
        {
            f_out(src, dst);
        }
        Samples {
            n_in: self.n_in,
            n_out: self.n_out,
            x,
            y,
        }
    }

    fn split_by_mask(&self, is_val: &[bool]) -> Result<(Samples, Samples), DataError> {
        let train = self.select((0..self.len()).filter(|&i| !is_val[i]));
        let val = self.select((0..self.len()).filter(|&i| is_val[i]));
        if train.is_empty() {
            return Err(DataError::BadSplit {
                reason: "the training set would be empty",
            });
        }
        if val.is_empty() {
            return Err(DataError::BadSplit {
                reason: "the validation set would be empty",
            });
        }
        Ok((train, val))
    }
}

fn check_finite(what: &'static str, values: &[f64]) -> Result<(), DataError> {
    match values.iter().position(|v| !v.is_finite()) {
        Some(index) => Err(DataError::NonFinite {
            what,
            index,
            value: values[index],
        }),
        None => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ten_samples() -> Samples {
        let x: Vec<f64> = (0..10).map(f64::from).collect();
        let y: Vec<f64> = (0..10).map(|i| f64::from(i) * 10.0).collect();
        Samples::new(1, 1, x, y).unwrap()
    }

    #[test]
    fn split_by_groups_keeps_whole_groups_together() {
        let s = ten_samples();
        let groups = [0, 0, 0, 1, 1, 1, 2, 2, 2, 2];
        let (train, val) = s.split_by_groups(&groups, &[1]).unwrap();
        assert_eq!(val.inputs(), &[3.0, 4.0, 5.0]);
        assert_eq!(train.inputs(), &[0.0, 1.0, 2.0, 6.0, 7.0, 8.0, 9.0]);
        assert_eq!(train.targets()[3], 60.0);
    }

    #[test]
    fn split_blocks_sends_every_second_contiguous_block_to_validation() {
        let s = ten_samples();
        // 5 blocks of 2: blocks 1 and 3 (samples 2,3 and 6,7) validate.
        let (train, val) = s.split_blocks(5, 2).unwrap();
        assert_eq!(val.inputs(), &[2.0, 3.0, 6.0, 7.0]);
        assert_eq!(train.len(), 6);
    }

    #[test]
    fn bad_shapes_and_splits_are_errors() {
        assert!(matches!(
            Samples::new(2, 1, vec![1.0, 2.0, 3.0], vec![1.0]),
            Err(DataError::Shape { .. })
        ));
        assert!(matches!(
            Samples::new(1, 1, vec![1.0, f64::NAN], vec![1.0, 2.0]),
            Err(DataError::NonFinite { index: 1, .. })
        ));
        assert!(Samples::new(0, 1, vec![], vec![]).is_err());
        assert!(Samples::from_rows(&[vec![1.0], vec![1.0, 2.0]], &[vec![1.0], vec![2.0]]).is_err());
        let s = ten_samples();
        assert!(s.split_by_groups(&[0; 9], &[0]).is_err());
        assert!(
            s.split_by_groups(&[0; 10], &[0]).is_err(),
            "empty training set"
        );
        assert!(s.split_blocks(1, 2).is_err());
        assert!(s.split_blocks(5, 6).is_err());
    }
}
