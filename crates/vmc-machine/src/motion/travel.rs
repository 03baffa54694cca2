//! Travel check: every point a plan reaches must lie within the axis travels.
//!
//! Lines are convex, so their end points bound them. Arcs are checked on their bounding box,
//! which includes the points where the angle crosses a multiple of π/2: an arc can bulge past a
//! limit while both its end points are inside. A tolerance of 1e-9 mm (1 pm) absorbs the
//! rounding of `c + r·cos θ` on programs that touch a limit exactly.
//!
//! Rotary axes turn linearly with the path within a segment, so a segment's end angles bound
//! it; [`check_rotary_travel`] checks them against the travel limits in degrees (tolerance
//! 1e-9°).

use super::{Geometry, MotionError, Plan, Segment};
use vmc_gcode::interp::LengthUnit;

/// The message of a move beyond the travel, in the program's unit `unit` and rounded as a
/// person reads it (µm in mm, a tenth of a thou in inches): `line 4: axis X reaches 580 mm,
/// outside travel [0, 560] mm`. `values_mm`: the position reached and the travel's minimum
/// and maximum, machine coordinates, mm.
pub fn travel_message(line: usize, axis: char, values_mm: [f64; 3], unit: LengthUnit) -> String {
    let [pos, min, max] = values_mm.map(|v| unit.number_mm(v));
    let u = unit.symbol();
    format!("line {line}: axis {axis} reaches {pos} {u}, outside travel [{min}, {max}] {u}")
}

/// Overshoot tolerated before a position counts as outside the travel (mm).
const TRAVEL_TOLERANCE_MM: f64 = 1e-9;

const AXIS_NAMES: [char; 3] = ['X', 'Y', 'Z'];

fn validate_travel(travel_min_mm: [f64; 3], travel_max_mm: [f64; 3]) -> Result<(), MotionError> {
    for i in 0..3 {
        let (min_mm, max_mm) = (travel_min_mm[i], travel_max_mm[i]);
        if !(min_mm.is_finite() && max_mm.is_finite() && min_mm < max_mm) {
            return Err(MotionError::InvalidTravel {
                axis: AXIS_NAMES[i],
                min_mm,
                max_mm,
            });
        }
    }
    Ok(())
}

/// The axes of the box `[lo, hi]` (the reach of source line `line`) that leave the travel, as
/// [`MotionError::AxisOutOfTravel`] errors in X, Y, Z order.
fn box_violations(
    line: usize,
    lo: [f64; 3],
    hi: [f64; 3],
    travel_min_mm: [f64; 3],
    travel_max_mm: [f64; 3],
) -> Vec<MotionError> {
    let mut out = Vec::new();
    for i in 0..3 {
        let (min_mm, max_mm) = (travel_min_mm[i], travel_max_mm[i]);
        let outside = if lo[i] < min_mm - TRAVEL_TOLERANCE_MM {
            Some(lo[i])
        } else if hi[i] > max_mm + TRAVEL_TOLERANCE_MM {
            Some(hi[i])
        } else {
            None
        };
        if let Some(pos_mm) = outside {
            out.push(MotionError::AxisOutOfTravel {
                line,
                axis: AXIS_NAMES[i],
                pos_mm,
                min_mm,
                max_mm,
            });
        }
    }
    out
}

/// Every axis on which `seg` leaves the travel `[travel_min_mm, travel_max_mm]`, as
/// [`MotionError::AxisOutOfTravel`] errors (X, Y, Z order; empty when inside). Errors with
/// [`MotionError::InvalidTravel`] when a travel range is not finite and increasing.
pub fn segment_travel_violations(
    seg: &Segment,
    travel_min_mm: [f64; 3],
    travel_max_mm: [f64; 3],
) -> Result<Vec<MotionError>, MotionError> {
    validate_travel(travel_min_mm, travel_max_mm)?;
    let (lo, hi) = match &seg.geometry {
        Geometry::Arc(arc) => arc.bounds_mm(),
        Geometry::Point | Geometry::Line { .. } => {
            let (a, b) = (seg.start_mm, seg.end_mm);
            (
                [a[0].min(b[0]), a[1].min(b[1]), a[2].min(b[2])],
                [a[0].max(b[0]), a[1].max(b[1]), a[2].max(b[2])],
            )
        }
    };
    Ok(box_violations(
        seg.line,
        lo,
        hi,
        travel_min_mm,
        travel_max_mm,
    ))
}

/// Checks that the whole plan stays within `[travel_min_mm, travel_max_mm]` on every axis;
/// reports the first offending segment (in time order) with the extreme position it reaches.
pub fn check_travel(
    plan: &Plan,
    travel_min_mm: [f64; 3],
    travel_max_mm: [f64; 3],
) -> Result<(), MotionError> {
    validate_travel(travel_min_mm, travel_max_mm)?;
    if plan.segments().is_empty() {
        let p = plan.start_mm();
        return match box_violations(0, p, p, travel_min_mm, travel_max_mm)
            .into_iter()
            .next()
        {
            Some(e) => Err(e),
            None => Ok(()),
        };
    }
    for seg in plan.segments() {
        if let Some(e) = segment_travel_violations(seg, travel_min_mm, travel_max_mm)?
            .into_iter()
            .next()
        {
            return Err(e);
        }
    }
    Ok(())
}

/// Overshoot tolerated before an angle counts as outside the travel (degrees).
const ROTARY_TRAVEL_TOLERANCE_DEG: f64 = 1e-9;

/// Checks that the rotary axes A, B, C stay within `travel_deg` (`[min, max]` degrees per axis,
/// `None` for an axis the machine lacks or that has no limit) over the whole plan; reports the
/// first move (in time order) that leaves it, with the angle it reaches.
pub fn check_rotary_travel(
    plan: &Plan,
    travel_deg: &[Option<(f64, f64)>; 3],
) -> Result<(), MotionError> {
    for seg in plan.segments() {
        for (i, limits) in travel_deg.iter().enumerate() {
            let Some((min_deg, max_deg)) = *limits else {
                continue;
            };
            for angle_deg in [seg.start_abc_deg[i], seg.end_abc_deg[i]] {
                if angle_deg < min_deg - ROTARY_TRAVEL_TOLERANCE_DEG
                    || angle_deg > max_deg + ROTARY_TRAVEL_TOLERANCE_DEG
                {
                    return Err(MotionError::RotaryOutOfTravel {
                        line: seg.line,
                        axis: super::ROTARY_AXES[i],
                        angle_deg,
                        min_deg,
                        max_deg,
                    });
                }
            }
        }
    }
    Ok(())
}
