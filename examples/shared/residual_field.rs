//! Diagnosis: which first-order field the hybrid's residual follows, per state. The four
//! diagonals of one state (separate runs from the same thermal history) are fitted together by
//! least squares: per error component an offset per diagonal plus a gradient common to the
//! state over a chosen subset of axes; the max |E| left after removing each fit tells which
//! gradient terms a probing cycle would have to estimate. Reads the twin's truth
//! (`error_after_um`): a diagnosis only, never an estimator.
use nalgebra::{DMatrix, DVector};
use vmc_machine::sim::PointRecord;

/// A choice of gradient terms: per component (X, Y, Z) the axes its gradient runs along.
pub struct FieldTerms {
    /// Its name in the printout.
    pub name: &'static str,
    /// Per component, the axes (0 X, 1 Y, 2 Z) of its gradient.
    pub axes: [&'static [usize]; 3],
}

/// The variants compared.
pub const VARIANTS: [FieldTerms; 12] = [
    FieldTerms {
        name: "offset",
        axes: [&[], &[], &[]],
    },
    FieldTerms {
        name: "Ex/dX",
        axes: [&[0], &[], &[]],
    },
    FieldTerms {
        name: "Ex/dY",
        axes: [&[1], &[], &[]],
    },
    FieldTerms {
        name: "Ex/dZ",
        axes: [&[2], &[], &[]],
    },
    FieldTerms {
        name: "Ex/dX,Ey/dY",
        axes: [&[0], &[1], &[]],
    },
    FieldTerms {
        name: "Ex full",
        axes: [&[0, 1, 2], &[], &[]],
    },
    FieldTerms {
        name: "Ez/dZ",
        axes: [&[], &[], &[2]],
    },
    FieldTerms {
        name: "Ez full",
        axes: [&[], &[], &[0, 1, 2]],
    },
    FieldTerms {
        name: "scales",
        axes: [&[0], &[1], &[2]],
    },
    FieldTerms {
        name: "Ex,Ez full",
        axes: [&[0, 1, 2], &[], &[0, 1, 2]],
    },
    FieldTerms {
        name: "Ez full,scales",
        axes: [&[0], &[1], &[0, 1, 2]],
    },
    FieldTerms {
        name: "all full",
        axes: [&[0, 1, 2], &[0, 1, 2], &[0, 1, 2]],
    },
];

/// Per run of one state (its four diagonals), the max |E| (µm) left after removing the fit
/// `terms`, and the fitted gradients per component (µm/m along the fitted axes, else 0).
pub fn fit(runs: &[&[PointRecord]], terms: &FieldTerms) -> (Vec<f64>, [[f64; 3]; 3]) {
    let n_runs = runs.len();
    let all: Vec<(usize, &PointRecord)> = runs
        .iter()
        .enumerate()
        .flat_map(|(d, pts)| pts.iter().map(move |p| (d, p)))
        .collect();
    let n = all.len() as f64;
    let centre = [0, 1, 2].map(|a| all.iter().map(|(_, p)| p.commanded_mm[a]).sum::<f64>() / n);
    let mut left: Vec<Vec<[f64; 3]>> = runs
        .iter()
        .map(|pts| pts.iter().map(|p| p.error_after_um.unwrap()).collect())
        .collect();
    let mut grads = [[0.0; 3]; 3];
    for k in 0..3 {
        let axes = terms.axes[k];
        let cols = n_runs + axes.len();
        let mut a = DMatrix::zeros(all.len(), cols);
        let mut b = DVector::zeros(all.len());
        for (i, (d, p)) in all.iter().enumerate() {
            a[(i, *d)] = 1.0;
            for (j, &ax) in axes.iter().enumerate() {
                // Metres, so the gradient comes out in µm/m.
                a[(i, n_runs + j)] = (p.commanded_mm[ax] - centre[ax]) * 1e-3;
            }
            b[i] = p.error_after_um.unwrap()[k];
        }
        let x = a.clone().svd(true, true).solve(&b, 1e-12).unwrap();
        let fitted = &a * &x;
        let mut i = 0;
        for run in left.iter_mut() {
            for e in run.iter_mut() {
                e[k] -= fitted[i];
                i += 1;
            }
        }
        for (j, &ax) in axes.iter().enumerate() {
            grads[k][ax] = x[n_runs + j];
        }
    }
    let max = left
        .iter()
        .map(|run| {
            run.iter()
                .map(|e| (e[0] * e[0] + e[1] * e[1] + e[2] * e[2]).sqrt())
                .fold(0.0, f64::max)
        })
        .collect();
    (max, grads)
}
