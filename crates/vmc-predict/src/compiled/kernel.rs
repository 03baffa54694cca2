//! The activation kernels of the compiled model: `e^{2s}` and `tanh(s)` over a block of hidden
//! units, exact to round-off, branch-free so that the compiler vectorises them.
//!
//! Model: `tanh(s) = 1 − 2/(e^{2s} + 1)`, the form of the query path (one exponential, absolute
//! error ~1e-16). The exponential here is not libm's: `x = 2s` is clamped to `[−40, 40]` (beyond
//! it the tanh rounds to exactly ±1 either way: `2/(e^{40} + 1) ≈ 8.5e-18` is below half an ulp of
//! 1), then split `x = k·ln 2 + r` with `k = round(x/ln 2)` (Cody–Waite: `ln 2` in two parts, the
//! high one with trailing zero bits so `k·ln2_hi` is exact for `|k| ≤ 58`), `|r| ≤ ln 2 / 2`, and
//! `e^x = 2^k·p(r)` with `p` the Taylor polynomial of degree 13 (truncation `< 4.3e-18` relative,
//! below the round-off), `2^k` assembled in the exponent bits. Measured against `f64::exp` over
//! the range: ≤ 2 ulp. NaN propagates (`clamp` keeps NaN; so does every step after it).
//!
//! Why not libm: `f64::exp` is an opaque call per unit (≈ 6 ns here); this form has no call and
//! no branch, so a block of units runs through SIMD lanes.
//!
//! The second kernel moves a block of activations by a small step of their arguments:
//! `e^{2(s+Δ)} = e^{2s}·e^{2Δ}` with `e^{2Δ}` from its Taylor polynomial of degree 6, exact to
//! round-off for `|2Δ| ≤` [`SMALL_STEP_MAX`] (`0.01⁷/7! ≈ 2e-18`). Products of exponentials keep
//! their relative errors (no cancellation), so a moved activation is as accurate as a fresh one,
//! up to one rounding per move.

/// Largest `|2Δ|` (twice the step of a hidden unit's argument) for which
/// [`move_exp2_block`] is exact to round-off.
pub const SMALL_STEP_MAX: f64 = 0.01;

/// `|2s|` beyond which `tanh(s)` is ±1 to the last bit (see the module doc).
const CLAMP_2S: f64 = 40.0;

/// `1.5·2⁵²`: adding it rounds a double of magnitude < 2⁵¹ to an integer held in the low bits of
/// the sum's mantissa.
const ROUND_MAGIC: f64 = 6_755_399_441_055_744.0;

/// `ln 2` with its low 32 mantissa bits cleared: `k·LN2_HI` is exact for `|k| < 2²⁰`.
const LN2_HI: f64 = f64::from_bits(std::f64::consts::LN_2.to_bits() & !0xffff_ffff);
/// The rest of `ln 2`, rounded: `ln 2 − LN2_HI` with `ln 2` to 60 digits
/// (`0.693147180559945309417232121458176568075500134360255254120680`), not `LN_2 − LN2_HI`,
/// which would carry the rounding of `LN_2` (2.3e-17) times `k` into `r`: 12 ulp at |k| = 57.
const LN2_LO: f64 = 4.749_325_039_031_672_6e-7;

/// `1/n!` for n = 13 down to 2 (Horner order).
const INV_FACT: [f64; 12] = [
    1.0 / 6_227_020_800.0,
    1.0 / 479_001_600.0,
    1.0 / 39_916_800.0,
    1.0 / 3_628_800.0,
    1.0 / 362_880.0,
    1.0 / 40_320.0,
    1.0 / 5_040.0,
    1.0 / 720.0,
    1.0 / 120.0,
    1.0 / 24.0,
    1.0 / 6.0,
    0.5,
];

/// `e^{2s}` for `s` clamped as in the module doc (exact to ~2 ulp; NaN stays NaN).
#[inline(always)]
pub fn exp2s(s: f64) -> f64 {
    let x = (2.0 * s).clamp(-CLAMP_2S, CLAMP_2S);
    // k = round(x / ln 2), as a double and as the integer in the low bits of `kr`.
    let kr = x * std::f64::consts::LOG2_E + ROUND_MAGIC;
    let k = kr - ROUND_MAGIC;
    let r = (x - k * LN2_HI) - k * LN2_LO;
    let mut p = INV_FACT[0];
    for c in &INV_FACT[1..] {
        p = p * r + c;
    }
    p = p * r + 1.0;
    p = p * r + 1.0;
    // 2^k: the biased exponent k + 1023 in the exponent field (|k| ≤ 58 after the clamp).
    let k_bits = kr.to_bits().wrapping_sub(ROUND_MAGIC.to_bits());
    let two_k = f64::from_bits(k_bits.wrapping_add(1023) << 52);
    p * two_k
}

/// `tanh(s)` from `e^{2s}` (`exp2s`): `1 − 2/(e^{2s} + 1)`.
#[inline(always)]
pub fn tanh_from_exp2s(e: f64) -> f64 {
    1.0 - 2.0 / (e + 1.0)
}

/// For each unit: `e[j] = e^{2 s[j]}` and `a[j] = tanh(s[j])` (slices of equal length).
#[inline]
pub fn exp2_tanh_block(s: &[f64], e: &mut [f64], a: &mut [f64]) {
    for ((s, e), a) in s.iter().zip(e.iter_mut()).zip(a.iter_mut()) {
        let x = exp2s(*s);
        *e = x;
        *a = tanh_from_exp2s(x);
    }
}

/// `e^{2Δ}` by its Taylor polynomial of degree 6 (exact to round-off for
/// `|2Δ| ≤` [`SMALL_STEP_MAX`]).
#[inline(always)]
fn exp_small(x: f64) -> f64 {
    let mut p = 1.0 / 720.0;
    p = p * x + 1.0 / 120.0;
    p = p * x + 1.0 / 24.0;
    p = p * x + 1.0 / 6.0;
    p = p * x + 0.5;
    p = p * x + 1.0;
    p * x + 1.0
}

/// Moves each unit from argument `s_old[j]` (with `e[j] = e^{2 s_old[j]}`) to `s_new[j]`:
/// `e[j] ← e[j]·e^{2(s_new[j] − s_old[j])}` and `a[j] ← tanh(s_new[j])`. The caller checks
/// first that every `|2(s_new − s_old)| ≤` [`SMALL_STEP_MAX`] ([`max_step`]).
#[inline]
pub fn move_exp2_block(s_old: &[f64], s_new: &[f64], e: &mut [f64], a: &mut [f64]) {
    for (((so, sn), e), a) in s_old.iter().zip(s_new).zip(e.iter_mut()).zip(a.iter_mut()) {
        let x = *e * exp_small(2.0 * (sn - so));
        *e = x;
        *a = tanh_from_exp2s(x);
    }
}

/// `max_j |2(s_new[j] − s_old[j])|`; NaN when any argument is NaN (so that a NaN never takes the
/// small-step path silently).
#[inline]
pub fn max_step(s_old: &[f64], s_new: &[f64]) -> f64 {
    let mut m = 0.0_f64;
    for (so, sn) in s_old.iter().zip(s_new) {
        let d = (2.0 * (sn - so)).abs();
        // `d > m` is false for NaN: carry it explicitly.
        m = if d > m || d.is_nan() { d } else { m };
    }
    m
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Distance in ulps between two finite positive doubles.
    fn ulps(a: f64, b: f64) -> u64 {
        a.to_bits().abs_diff(b.to_bits())
    }

    #[test]
    fn the_exponential_is_within_two_ulp_of_libm_over_the_clamped_range() {
        let mut worst = 0;
        // |2s| ≤ 40: the whole range before the clamp.
        for i in -399_990..=399_990 {
            let s = f64::from(i) * 5e-5 + 1.234_567e-7;
            let got = exp2s(s);
            let want = (2.0 * s).exp();
            worst = worst.max(ulps(got, want));
        }
        assert!(worst <= 2, "worst {worst} ulp");
        // The split rounds back to `LN_2`, the low part adds what `LN_2` lost.
        assert_eq!(LN2_HI + LN2_LO, std::f64::consts::LN_2);
        assert_ne!(LN2_LO, std::f64::consts::LN_2 - LN2_HI);
        assert_eq!(LN2_HI.to_bits() & 0xffff_ffff, 0);
    }

    #[test]
    fn tanh_saturates_exactly_where_the_query_path_does() {
        for s in [20.0, 20.5, 25.0, 1e3, 1e300, f64::INFINITY] {
            let libm = 1.0 - 2.0 / ((2.0 * s).exp() + 1.0);
            assert_eq!(tanh_from_exp2s(exp2s(s)), libm, "{s}");
            assert_eq!(tanh_from_exp2s(exp2s(-s)), -libm, "{s}");
        }
        assert!(exp2s(f64::NAN).is_nan());
        assert!(tanh_from_exp2s(exp2s(f64::NAN)).is_nan());
    }

    #[test]
    fn tanh_is_the_query_paths_formula_to_round_off() {
        for i in -20_000..=20_000 {
            let s = f64::from(i) * 1e-3;
            let got = tanh_from_exp2s(exp2s(s));
            // The library's query path: the same formula on libm's exponential.
            let libm = 1.0 - 2.0 / ((2.0 * s).exp() + 1.0);
            assert!((got - libm).abs() <= 4.5e-16, "{s}: {got} vs {libm}");
            assert!((got - s.tanh()).abs() < 1e-15, "{s}: {got} vs {}", s.tanh());
        }
    }

    #[test]
    fn a_small_move_equals_a_fresh_evaluation_to_round_off() {
        let s_old: Vec<f64> = (0..16).map(|j| -3.0 + 0.4 * f64::from(j)).collect();
        for step in [1e-9, -3e-6, 2e-4, -0.004, 0.0049] {
            let s_new: Vec<f64> = s_old.iter().map(|s| s + step).collect();
            assert!(max_step(&s_old, &s_new) <= SMALL_STEP_MAX);
            let (mut e, mut a) = (vec![0.0; 16], vec![0.0; 16]);
            exp2_tanh_block(&s_old, &mut e, &mut a);
            move_exp2_block(&s_old, &s_new, &mut e, &mut a);
            for (j, s) in s_new.iter().enumerate() {
                let want = (2.0 * s).exp();
                assert!(ulps(e[j], want) <= 4, "{s}: {} vs {want}", e[j]);
                assert!((a[j] - s.tanh()).abs() <= 4e-16, "{s}");
            }
        }
    }

    #[test]
    fn a_nan_argument_is_never_taken_for_a_small_step() {
        assert!(max_step(&[0.0, 1.0], &[0.0, f64::NAN]).is_nan());
        assert!(max_step(&[f64::NAN, 1.0], &[0.0, 1.0]).is_nan());
        assert!((max_step(&[0.0, 1.0], &[0.001, 0.999]) - 0.002).abs() < 1e-15);
    }
}
