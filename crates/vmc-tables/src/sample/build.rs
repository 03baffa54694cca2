//! Sampling the model into tables and checking them (model in the `sample` module doc).

use vmc_predict::predictor::ErrorPredictor;

use super::{
    CrossTable, Grid, InterpolationCheck, OwnAxisTable, Residual, SampleError, SamplingSpec,
    TableSet, VolumeCheck, AXIS_NAMES,
};
use crate::number::{interpolate, quantise_mm, Direction};

/// Samples `model`, which has observed the readings of the thermal state, into own-axis and
/// cross tables, and checks them against it (see the module doc).
///
/// # Errors
/// An unusable specification (travel, reference outside the travel, spacing, point count,
/// check settings), or a model that answers NaN (no readings observed) or a non-finite
/// reversal.
pub fn sample_tables<P: ErrorPredictor + ?Sized>(
    model: &mut P,
    spec: &SamplingSpec,
) -> Result<TableSet, SampleError> {
    let grids = check_spec(spec)?;
    let q_ref = spec.reference_mm;
    let e_ref = predict(model, q_ref)?;
    let shift = model.negative_approach_shift_mm();
    if shift.iter().any(|s| !s.is_finite()) {
        return Err(SampleError::BadReversal { shift_mm: shift });
    }
    let mut own = Vec::with_capacity(3);
    let mut cross = Vec::with_capacity(6);
    for (k, grid) in grids.iter().enumerate() {
        // e_line[i] = E at q_ref with q_k at grid position i.
        let e_line = grid
            .positions_mm()
            .into_iter()
            .map(|x| predict(model, along(q_ref, k, x)))
            .collect::<Result<Vec<_>, _>>()?;
        let forward_mm: Vec<f64> = e_line.iter().map(|e| quantise_mm(-e[k])).collect();
        let reverse_mm = e_line
            .iter()
            .map(|e| quantise_mm(-(e[k] + shift[k])))
            .collect();
        let mut corrections: [Vec<f64>; 3] = std::array::from_fn(|j| {
            if j == k {
                forward_mm.clone()
            } else {
                e_line
                    .iter()
                    .map(|e| quantise_mm(-(e[j] - e_ref[j])))
                    .collect()
            }
        });
        let checks = check_line(model, spec, *grid, k, q_ref, e_ref, &corrections)?;
        own.push(OwnAxisTable {
            axis: k,
            grid: *grid,
            forward_mm,
            reverse_mm,
            check: checks[k],
        });
        for j in (0..3).filter(|&j| j != k) {
            cross.push(CrossTable {
                output_axis: j,
                input_axis: k,
                grid: *grid,
                correction_mm: std::mem::take(&mut corrections[j]),
                check: checks[j],
            });
        }
    }
    // Ordered by output axis, then input axis: the order a reader of one axis's tables wants.
    cross.sort_by_key(|t| (t.output_axis, t.input_axis));
    let mut set = TableSet {
        reference_mm: q_ref,
        reference_error_mm: e_ref,
        reversal_shift_mm: shift,
        own,
        cross,
        volume: VolumeCheck::default(),
    };
    set.volume = check_volume(model, spec, &set)?;
    Ok(set)
}

/// The grids of the three axes, after checking the rest of the specification.
fn check_spec(spec: &SamplingSpec) -> Result<[Grid; 3], SampleError> {
    if spec.check_subdivisions == 0 || spec.check_subdivisions > 1000 {
        return Err(SampleError::BadSetting {
            field: "check_subdivisions",
            reason: format!("{} (1 to 1000)", spec.check_subdivisions),
        });
    }
    if !(2..=50).contains(&spec.volume_points_per_axis) {
        return Err(SampleError::BadSetting {
            field: "volume_points_per_axis",
            reason: format!("{} (2 to 50)", spec.volume_points_per_axis),
        });
    }
    let mut grids = Vec::with_capacity(3);
    for (k, travel) in spec.travel.iter().enumerate() {
        let grid = Grid::with_spacing(k, *travel, spec.spacing)?;
        let r = spec.reference_mm[k];
        if !(r >= travel.min_mm && r <= travel.max_mm) {
            return Err(SampleError::ReferenceOutsideTravel {
                axis: AXIS_NAMES[k],
                reference_mm: r,
                min_mm: travel.min_mm,
                max_mm: travel.max_mm,
            });
        }
        grids.push(grid);
    }
    Ok([grids[0], grids[1], grids[2]])
}

/// `q` with axis `k` at `x_mm`.
fn along(mut q: [f64; 3], k: usize, x_mm: f64) -> [f64; 3] {
    q[k] = x_mm;
    q
}

fn predict<P: ErrorPredictor + ?Sized>(
    model: &mut P,
    q_mm: [f64; 3],
) -> Result<[f64; 3], SampleError> {
    let e_mm = model.predict_error_mm(q_mm);
    if e_mm.iter().all(|e| e.is_finite()) {
        Ok(e_mm)
    } else {
        Err(SampleError::NoPrediction { q_mm, e_mm })
    }
}

/// The interpolation check of the three tables along input axis `k` (own table `k`, cross
/// tables `j ≠ k`): the model at `check_subdivisions` points per interval against the tables.
fn check_line<P: ErrorPredictor + ?Sized>(
    model: &mut P,
    spec: &SamplingSpec,
    grid: Grid,
    k: usize,
    q_ref: [f64; 3],
    e_ref: [f64; 3],
    corrections: &[Vec<f64>; 3],
) -> Result<[InterpolationCheck; 3], SampleError> {
    let positions = grid.positions_mm();
    let sub = spec.check_subdivisions;
    let mut checks = [InterpolationCheck {
        max_abs_um: 0.0,
        at_mm: positions[0],
        samples: 0,
    }; 3];
    let n_checks = (grid.points - 1) * sub + 1;
    for s in 0..n_checks {
        let (i, f) = (s / sub, (s % sub) as f64 / sub as f64);
        let x = if i + 1 < grid.points {
            positions[i] + f * (positions[i + 1] - positions[i])
        } else {
            positions[grid.points - 1]
        };
        let e = predict(model, along(q_ref, k, x))?;
        for (j, check) in checks.iter_mut().enumerate() {
            let model_c = if j == k { -e[j] } else { -(e[j] - e_ref[j]) };
            let diff_um = (interpolate(&positions, &corrections[j], x) - model_c).abs() * 1e3;
            check.samples += 1;
            if diff_um > check.max_abs_um {
                check.max_abs_um = diff_um;
                check.at_mm = x;
            }
        }
    }
    Ok(checks)
}

/// The residual of the table set over a grid of the volume (positive approach).
fn check_volume<P: ErrorPredictor + ?Sized>(
    model: &mut P,
    spec: &SamplingSpec,
    set: &TableSet,
) -> Result<VolumeCheck, SampleError> {
    let m = spec.volume_points_per_axis;
    let coord = |k: usize, i: usize| {
        let t = spec.travel[k];
        t.min_mm + (t.max_mm - t.min_mm) * i as f64 / (m - 1) as f64
    };
    let mut model_sq = [0.0; 3];
    let mut model_max = [0.0f64; 3];
    let mut own_sq = [0.0; 3];
    let mut own_max = [0.0f64; 3];
    let mut all_sq = [0.0; 3];
    let mut all_max = [0.0f64; 3];
    for ix in 0..m {
        for iy in 0..m {
            for iz in 0..m {
                let q = [coord(0, ix), coord(1, iy), coord(2, iz)];
                let e = predict(model, q)?;
                for j in 0..3 {
                    let own = e[j] + set.own_correction_mm(j, q[j], Direction::Positive);
                    let cross: f64 = (0..3)
                        .filter(|&k| k != j)
                        .map(|k| set.cross_correction_mm(j, k, q[k]))
                        .sum();
                    let all = own + cross;
                    let (e_um, own_um, all_um) = (e[j] * 1e3, own * 1e3, all * 1e3);
                    model_sq[j] += e_um * e_um;
                    model_max[j] = model_max[j].max(e_um.abs());
                    own_sq[j] += own_um * own_um;
                    own_max[j] = own_max[j].max(own_um.abs());
                    all_sq[j] += all_um * all_um;
                    all_max[j] = all_max[j].max(all_um.abs());
                }
            }
        }
    }
    let n = (m * m * m) as f64;
    let rms = |sq: [f64; 3]| sq.map(|s| (s / n).sqrt());
    Ok(VolumeCheck {
        points: m * m * m,
        model_max_abs_um: model_max,
        model_rms_um: rms(model_sq),
        own_axis_only: Residual {
            max_abs_um: own_max,
            rms_um: rms(own_sq),
        },
        own_and_cross: Residual {
            max_abs_um: all_max,
            rms_um: rms(all_sq),
        },
    })
}

#[cfg(test)]
mod tests;
