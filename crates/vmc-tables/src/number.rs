//! Numbers as the tables print them, and the linear interpolation both controllers apply.
//!
//! **Precision.** Every position and compensation value is written with 6 decimals of a
//! millimetre: a resolution of 1e-6 mm = 1 nm, three orders below the ~1 µm a compensation aims
//! at, and far below any controller's position resolution (LinuxCNC and Siemens both hold
//! positions as binary floating point). A value is first *quantised* to that grid
//! ([`quantise_mm`]), then printed: the printed decimal is then exactly the quantised value, a
//! reader gets it back to within one rounding of binary floating point (≈ 1e-13 mm for
//! positions within ±1e5 mm), and everything computed from the tables in memory (the
//! interpolation reports) is computed from what the controller will read.
//!
//! **Interpolation.** Both controllers interpolate linearly between neighbouring points and
//! hold the end values beyond the ends ([`interpolate`]).

use serde::{Deserialize, Serialize};

/// Resolution of every printed position and value, mm (1e-6 mm = 1 nm).
pub const RESOLUTION_MM: f64 = 1e-6;

/// Largest |position| or |value| the tables accept, mm (100 m). Why: beyond it the 1 nm grid is
/// no longer exact in binary floating point (1e5 mm × 1e6 = 1e11 < 2⁵³), and no machine axis
/// is that long.
pub const MAX_ABS_MM: f64 = 1e5;

/// The direction of motion of an axis (a joint, a base axis), which selects a table column or
/// a direction-dependent table.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum Direction {
    /// Moving in the positive direction (LinuxCNC's "forward" column).
    Positive,
    /// Moving in the negative direction (LinuxCNC's "reverse" column).
    Negative,
}

/// `x_mm` on the 1 nm grid (nearest multiple of [`RESOLUTION_MM`]), never negative zero.
#[must_use]
pub fn quantise_mm(x_mm: f64) -> f64 {
    // `+ 0.0` turns a rounded −0.0 into +0.0, so that nothing prints as "-0".
    (x_mm * 1e6).round() / 1e6 + 0.0
}

/// `x_mm` quantised and printed with exactly 6 decimals (LinuxCNC tables: every column the same
/// width of precision).
#[must_use]
pub fn fixed_mm(x_mm: f64) -> String {
    format!("{:.6}", quantise_mm(x_mm))
}

/// `x_mm` quantised and printed in its shortest decimal form with at least `min_decimals`
/// decimals: `0.01`, `0`, `-400.0` (the layout of the Siemens manual's examples: positions with
/// one decimal at least, compensation values as short as they are).
#[must_use]
pub fn short_mm(x_mm: f64, min_decimals: usize) -> String {
    let full = format!("{:.6}", quantise_mm(x_mm));
    let (int, frac) = full.split_once('.').unwrap_or((full.as_str(), ""));
    let mut frac = frac.trim_end_matches('0').to_string();
    while frac.len() < min_decimals {
        frac.push('0');
    }
    if frac.is_empty() {
        int.to_string()
    } else {
        format!("{int}.{frac}")
    }
}

/// Linear interpolation of the points `(positions_mm[i], values_mm[i])` at `x_mm`, the end
/// values held beyond the ends. `positions_mm` must be strictly ascending and as long as
/// `values_mm`, with at least one point (the tables' constructors guarantee it).
#[must_use]
pub fn interpolate(positions_mm: &[f64], values_mm: &[f64], x_mm: f64) -> f64 {
    debug_assert_eq!(positions_mm.len(), values_mm.len());
    let n = positions_mm.len();
    if x_mm <= positions_mm[0] {
        return values_mm[0];
    }
    if x_mm >= positions_mm[n - 1] {
        return values_mm[n - 1];
    }
    // First index whose position is > x: the interval is [i − 1, i].
    let i = positions_mm.partition_point(|&p| p <= x_mm);
    let (x0, x1) = (positions_mm[i - 1], positions_mm[i]);
    let (y0, y1) = (values_mm[i - 1], values_mm[i]);
    y0 + (y1 - y0) * (x_mm - x0) / (x1 - x0)
}

/// A name the controllers' files can carry: ASCII letters, digits and `_`, starting with a
/// letter (a Siemens machine axis name such as `AX1` or `X1`; a LinuxCNC file name stem).
#[must_use]
pub fn is_plain_name(name: &str) -> bool {
    let mut chars = name.chars();
    chars.next().is_some_and(|c| c.is_ascii_alphabetic())
        && chars.all(|c| c.is_ascii_alphanumeric() || c == '_')
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quantising_rounds_to_the_nanometre_and_never_gives_negative_zero() {
        assert_eq!(quantise_mm(0.012_345_64), 0.012_346);
        assert_eq!(quantise_mm(-0.000_000_4), 0.0);
        assert!(quantise_mm(-0.000_000_4).is_sign_positive());
        assert_eq!(fixed_mm(-0.000_000_4), "0.000000");
        assert_eq!(fixed_mm(-12.5), "-12.500000");
    }

    #[test]
    fn short_form_prints_like_the_siemens_examples() {
        assert_eq!(short_mm(0.0, 0), "0");
        assert_eq!(short_mm(0.01, 0), "0.01");
        assert_eq!(short_mm(0.012, 0), "0.012");
        assert_eq!(short_mm(-400.0, 1), "-400.0");
        assert_eq!(short_mm(6.73, 1), "6.73");
        assert_eq!(short_mm(58.0, 1), "58.0");
        assert_eq!(short_mm(-0.000_000_2, 1), "0.0");
        assert_eq!(short_mm(1.234_567_8, 0), "1.234568");
    }

    #[test]
    fn interpolation_is_linear_inside_and_holds_the_end_values_outside() {
        let x = [0.0, 10.0, 30.0];
        let y = [1.0, 3.0, -1.0];
        assert_eq!(interpolate(&x, &y, -5.0), 1.0);
        assert_eq!(interpolate(&x, &y, 0.0), 1.0);
        assert_eq!(interpolate(&x, &y, 5.0), 2.0);
        assert_eq!(interpolate(&x, &y, 10.0), 3.0);
        assert_eq!(interpolate(&x, &y, 20.0), 1.0);
        assert_eq!(interpolate(&x, &y, 30.0), -1.0);
        assert_eq!(interpolate(&x, &y, 99.0), -1.0);
    }

    #[test]
    fn plain_names_are_letters_digits_and_underscores_after_a_letter() {
        assert!(is_plain_name("AX1"));
        assert!(is_plain_name("x_comp"));
        assert!(!is_plain_name("1X"));
        assert!(!is_plain_name(""));
        assert!(!is_plain_name("AX1)"));
        assert!(!is_plain_name("a b"));
    }
}
