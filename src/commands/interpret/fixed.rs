//! Fixed-point text of a number with 4 decimals, the `%.4f` of LinuxCNC's `rs274` and Rust's
//! `{:.4}`, without going through the general formatter.
//!
//! The value is scaled by 10⁴ and rounded to an integer, which is then written digit by digit.
//! The scaled product carries a rounding error of at most one unit in its last place, so its
//! rounding agrees with the exact decimal rounding unless its fraction lies within that error of
//! one half; those values (and values too large for the integer path, and non-finite ones) go
//! through `{:.4}`, so the text is always the same as `{:.4}`'s. Negative zero, and negative
//! values that round to zero, keep their sign (`-0.0000`), as both `printf` and `{:.4}` do.

use std::io::Write;

/// Largest |scaled value| taken by the integer path: well inside the integers an f64 holds
/// exactly (2⁵³), so the product's error stays below 2⁻⁴ of a unit.
const MAX_SCALED: f64 = 4.0e15;

/// Appends `x` with 4 decimals to `buf` (the text of `format!("{x:.4}")`).
pub fn push_fixed4(buf: &mut Vec<u8>, x: f64) {
    let scaled = x.abs() * 1e4;
    if !scaled.is_finite() || scaled >= MAX_SCALED {
        // Not finite, or too large for the integer path.
        let _ = write!(buf, "{x:.4}");
        return;
    }
    let floor = scaled.floor();
    let frac = scaled - floor;
    // Within this distance of a tie the product's rounding error could decide the side.
    let doubt = f64::EPSILON * 4.0 * scaled.max(1.0);
    if (frac - 0.5).abs() <= doubt {
        let _ = write!(buf, "{x:.4}");
        return;
    }
    let units = if frac > 0.5 { floor + 1.0 } else { floor } as u64;
    if x.is_sign_negative() {
        buf.push(b'-');
    }
    push_u64(buf, units / 10_000);
    buf.push(b'.');
    let decimals = units % 10_000;
    buf.extend_from_slice(&[
        b'0' + (decimals / 1000) as u8,
        b'0' + (decimals / 100 % 10) as u8,
        b'0' + (decimals / 10 % 10) as u8,
        b'0' + (decimals % 10) as u8,
    ]);
}

/// Appends the decimal digits of `n`.
pub fn push_u64(buf: &mut Vec<u8>, mut n: u64) {
    let mut digits = [0u8; 20];
    let mut i = digits.len();
    loop {
        i -= 1;
        digits[i] = b'0' + (n % 10) as u8;
        n /= 10;
        if n == 0 {
            break;
        }
    }
    buf.extend_from_slice(&digits[i..]);
}

/// Appends `n` right-aligned in a field of `width` characters (the text of `{n:width$}`).
pub fn push_u64_padded(buf: &mut Vec<u8>, n: u64, width: usize) {
    let start = buf.len();
    push_u64(buf, n);
    let len = buf.len() - start;
    if len < width {
        buf.splice(start..start, std::iter::repeat_n(b' ', width - len));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn fixed4(x: f64) -> String {
        let mut buf = Vec::new();
        push_fixed4(&mut buf, x);
        String::from_utf8(buf).unwrap()
    }

    /// A seeded xorshift stream (no dependency for a test's numbers).
    fn stream(mut state: u64) -> impl FnMut() -> u64 {
        move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            state
        }
    }

    #[test]
    fn the_text_is_that_of_the_general_formatter_on_program_like_values() {
        let mut next = stream(0x9e37_79b9_7f4a_7c15);
        for _ in 0..200_000 {
            let r = next();
            // Coordinates with up to 6 decimals, in ±10 m, and their negatives.
            let x = (r % 20_000_000_000) as f64 * 1e-6 - 10_000.0;
            assert_eq!(fixed4(x), format!("{x:.4}"), "{x:e}");
        }
    }

    #[test]
    fn the_text_is_that_of_the_general_formatter_on_arbitrary_bit_patterns() {
        let mut next = stream(12345);
        for _ in 0..200_000 {
            let x = f64::from_bits(next());
            assert_eq!(fixed4(x), format!("{x:.4}"), "{:#x}", x.to_bits());
        }
    }

    #[test]
    fn ties_signed_zeros_and_limits_read_as_the_general_formatter() {
        let cases = [
            0.0,
            -0.0,
            -0.00004,
            0.00005,
            -0.00005,
            1.03125,
            2.5e-5,
            0.12345,
            0.99995,
            9.99995,
            1.0e11,
            -1.0e11,
            4.0e11,
            1.0e300,
            f64::MIN_POSITIVE,
            f64::MAX,
            f64::NAN,
            f64::INFINITY,
            f64::NEG_INFINITY,
        ];
        for x in cases {
            assert_eq!(fixed4(x), format!("{x:.4}"), "{x:e}");
        }
    }

    #[test]
    fn integers_are_padded_as_a_width_is() {
        for (n, w) in [(0u64, 5usize), (7, 5), (12345, 5), (123_456, 5), (42, 0)] {
            let mut buf = Vec::new();
            push_u64_padded(&mut buf, n, w);
            assert_eq!(String::from_utf8(buf).unwrap(), format!("{n:w$}"));
        }
    }
}
