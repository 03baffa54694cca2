//! Arc centre in the active plane, with LinuxCNC's acceptance rules.
//!
//! Coordinates are (first, second) plane coordinates in mm: (X, Y) for G17, (Z, X) for G18,
//! (Y, Z) for G19. Tolerances are LinuxCNC's, stated in the program's units and converted here:
//! - centre form: r1 = |start − c|, r2 = |end − c|; zero radius if r1 or r2 < `RADIUS_TOL`;
//!   rejected if |r1 − r2| > 100·`SPIRAL_ABS_TOL`, or if |r1 − r2|/max(r1, r2) > 0.1 % **and**
//!   |r1 − r2| > `SPIRAL_ABS_TOL` (`SPIRAL_ABS_TOL` = 0.02·√2 mm or 0.002·√2 in);
//! - radius form: start ≠ end; rejected if half the chord exceeds |R| by more than
//!   `RADIUS_TOL` (0.00005 in = 0.00127 mm); if it is within that, the centre is the chord
//!   midpoint. R > 0 gives the short arc (≤ 180°), R < 0 the long one:
//!   c = m + √(R² − h²)·n, with m the chord midpoint, h half the chord and n the unit normal to
//!   the chord on the right of start→end for (G2, R>0) and (G3, R<0), on the left otherwise.

/// mm per inch.
pub(super) const MM_PER_INCH: f64 = 25.4;
/// LinuxCNC `RADIUS_TOLERANCE_INCH` (in).
const RADIUS_TOL_IN: f64 = 0.00005;
/// LinuxCNC `CENTER_ARC_RADIUS_TOLERANCE_MM` (mm).
const SPIRAL_ABS_TOL_MM: f64 = 2.0 * 0.01 * std::f64::consts::SQRT_2;
/// LinuxCNC `CENTER_ARC_RADIUS_TOLERANCE_INCH` (in).
const SPIRAL_ABS_TOL_IN: f64 = 2.0 * 0.001 * std::f64::consts::SQRT_2;
/// LinuxCNC `SPIRAL_RELATIVE_TOLERANCE` (fraction).
const SPIRAL_REL_TOL: f64 = 0.001;

/// How the centre is given.
#[derive(Debug, Clone, Copy)]
pub(super) enum ArcForm {
    /// Centre in plane coordinates (mm, machine frame).
    Center([f64; 2]),
    /// Signed radius (mm).
    Radius(f64),
}

/// Why an arc cannot be made. Lengths in mm.
#[derive(Debug, Clone, PartialEq)]
pub(super) enum ArcError {
    /// Start or end lies (almost) on the centre.
    ZeroRadius { r1_mm: f64, r2_mm: f64 },
    /// The end is not on the circle through the start.
    RadiusMismatch { r1_mm: f64, r2_mm: f64 },
    /// Radius form with start = end: the centre is undetermined.
    RadiusFormFullCircle,
    /// Radius form whose |R| is shorter than half the chord.
    RadiusTooSmall { r_mm: f64, half_chord_mm: f64 },
}

/// Centre of the arc from `start` to `end` (plane coordinates, mm). `inch` selects the
/// tolerances of G20 programs.
pub(super) fn arc_center(
    start: [f64; 2],
    end: [f64; 2],
    form: ArcForm,
    clockwise: bool,
    inch: bool,
) -> Result<[f64; 2], ArcError> {
    let radius_tol_mm = RADIUS_TOL_IN * MM_PER_INCH;
    match form {
        ArcForm::Center(c) => {
            let r1_mm = dist(start, c);
            let r2_mm = dist(end, c);
            if r1_mm < radius_tol_mm || r2_mm < radius_tol_mm {
                return Err(ArcError::ZeroRadius { r1_mm, r2_mm });
            }
            let abs_tol_mm = if inch {
                SPIRAL_ABS_TOL_IN * MM_PER_INCH
            } else {
                SPIRAL_ABS_TOL_MM
            };
            let abs_err = (r1_mm - r2_mm).abs();
            let rel_err = abs_err / r1_mm.max(r2_mm);
            if abs_err > 100.0 * abs_tol_mm || (rel_err > SPIRAL_REL_TOL && abs_err > abs_tol_mm) {
                return Err(ArcError::RadiusMismatch { r1_mm, r2_mm });
            }
            Ok(c)
        }
        ArcForm::Radius(r_mm) => {
            if start == end {
                return Err(ArcError::RadiusFormFullCircle);
            }
            let abs_r = r_mm.abs();
            let mid = [(start[0] + end[0]) / 2.0, (start[1] + end[1]) / 2.0];
            let mut half = dist(mid, end);
            if half - abs_r > radius_tol_mm || abs_r < radius_tol_mm {
                return Err(ArcError::RadiusTooSmall {
                    r_mm,
                    half_chord_mm: half,
                });
            }
            half = half.min(abs_r);
            let chord_angle = (end[1] - start[1]).atan2(end[0] - start[0]);
            let right = clockwise == (r_mm > 0.0);
            let normal = if right {
                chord_angle - std::f64::consts::FRAC_PI_2
            } else {
                chord_angle + std::f64::consts::FRAC_PI_2
            };
            let offset = (abs_r * abs_r - half * half).max(0.0).sqrt();
            Ok([
                mid[0] + offset * normal.cos(),
                mid[1] + offset * normal.sin(),
            ])
        }
    }
}

fn dist(a: [f64; 2], b: [f64; 2]) -> f64 {
    (a[0] - b[0]).hypot(a[1] - b[1])
}

#[cfg(test)]
mod tests {
    use super::*;

    /// 1e-9 mm = 1 pm: pure floating-point noise on 100 mm coordinates.
    const TOL_MM: f64 = 1e-9;

    fn close(a: [f64; 2], b: [f64; 2]) -> bool {
        dist(a, b) < TOL_MM
    }

    #[test]
    fn positive_radius_cw_quarter_from_origin_has_centre_below_the_chord() {
        // G2 from (0,0) to (10,10) R10: short cw arc, centre (10,0).
        let c = arc_center([0.0, 0.0], [10.0, 10.0], ArcForm::Radius(10.0), true, false).unwrap();
        assert!(close(c, [10.0, 0.0]), "{c:?}");
    }

    #[test]
    fn negative_radius_takes_the_other_centre() {
        let c = arc_center(
            [0.0, 0.0],
            [10.0, 10.0],
            ArcForm::Radius(-10.0),
            true,
            false,
        )
        .unwrap();
        assert!(close(c, [0.0, 10.0]), "{c:?}");
        let c = arc_center(
            [0.0, 0.0],
            [10.0, 10.0],
            ArcForm::Radius(10.0),
            false,
            false,
        )
        .unwrap();
        assert!(close(c, [0.0, 10.0]), "{c:?}");
        let c = arc_center(
            [0.0, 0.0],
            [10.0, 10.0],
            ArcForm::Radius(-10.0),
            false,
            false,
        )
        .unwrap();
        assert!(close(c, [10.0, 0.0]), "{c:?}");
    }

    #[test]
    fn radius_a_hair_short_of_a_semicircle_snaps_to_the_midpoint() {
        // LinuxCNC RADIUS_TOLERANCE_INCH = 0.00005 in = 0.00127 mm: R 0.001 mm short of half
        // the 20 mm chord is a semicircle, 0.0015 mm short is not.
        let c = arc_center([0.0, 0.0], [20.0, 0.0], ArcForm::Radius(9.999), true, false).unwrap();
        assert!(close(c, [10.0, 0.0]), "{c:?}");
        let e = arc_center(
            [0.0, 0.0],
            [20.0, 0.0],
            ArcForm::Radius(9.9985),
            true,
            false,
        );
        assert!(matches!(e, Err(ArcError::RadiusTooSmall { .. })), "{e:?}");
    }

    #[test]
    fn radius_clearly_too_small_is_rejected() {
        let e = arc_center([0.0, 0.0], [20.0, 0.0], ArcForm::Radius(9.99), true, false);
        assert!(matches!(e, Err(ArcError::RadiusTooSmall { .. })), "{e:?}");
    }

    #[test]
    fn radius_form_with_equal_ends_is_rejected() {
        let e = arc_center([1.0, 1.0], [1.0, 1.0], ArcForm::Radius(5.0), true, false);
        assert_eq!(e, Err(ArcError::RadiusFormFullCircle));
    }

    #[test]
    fn zero_radius_centre_is_rejected() {
        let e = arc_center(
            [1.0, 1.0],
            [3.0, 1.0],
            ArcForm::Center([1.0, 1.0]),
            true,
            false,
        );
        assert!(matches!(e, Err(ArcError::ZeroRadius { .. })));
    }

    #[test]
    fn linuxcnc_good_and_bad_arc_cases_are_separated_at_the_same_place() {
        // interp/good and interp/bad of the LinuxCNC corpus, metric (mm) and imperial (inch in mm).
        let s = std::f64::consts::SQRT_2;
        let run = |end: f64, i: f64, inch: bool| {
            let k = if inch { MM_PER_INCH } else { 1.0 };
            arc_center(
                [0.0, 0.0],
                [end * k, 0.0],
                ArcForm::Center([i * k, 0.0]),
                true,
                inch,
            )
        };
        assert!(run(6000.0, 3000.0 + 100.0 * 0.0099 * s, false).is_ok());
        assert!(run(6000.0, 3000.0 + 100.0 * 0.0101 * s, false).is_err());
        assert!(run(2000.0, 0.9995 * 1000.0, false).is_ok());
        assert!(run(2000.0, 0.9985 * 1000.0, false).is_err());
        assert!(run(50.0, 25.0 - 0.0099 * s, false).is_ok());
        assert!(run(50.0, 25.0 - 0.0101 * s, false).is_err());
        assert!(run(600.0, 300.0 + 100.0 * 0.00099 * s, true).is_ok());
        assert!(run(600.0, 300.0 + 100.0 * 0.00101 * s, true).is_err());
        assert!(run(200.0, 0.9995 * 100.0, true).is_ok());
        assert!(run(200.0, 0.9985 * 100.0, true).is_err());
        assert!(run(5.0, 2.5 - 0.00099 * s, true).is_ok());
        assert!(run(5.0, 2.5 - 0.00101 * s, true).is_err());
    }
}
