//! The activation kernels of the compiled model: `e^{2s}` and `tanh(s)` of hidden units, exact to
//! round-off, branch-free, four units at a time ([`Lane`]) so that they run through SIMD lanes.
//!
//! Model: `tanh(s) = 1 − 2/(e^{2s} + 1)`, the form of the library's query path (one exponential,
//! absolute error ~1e-16). The exponential here is not libm's: `x = 2s` is clamped to
//! `[−40, 40]` (beyond it the tanh rounds to exactly ±1 either way: `2/(e^{40} + 1) ≈ 8.5e-18` is
//! below half an ulp of 1), then split `x = k·ln 2 + r` with `k = round(x/ln 2)` (Cody–Waite:
//! `ln 2` in two parts, the high one with 32 trailing zero bits so `k·ln2_hi` is exact),
//! `|r| ≤ ln 2 / 2`, and `e^x = 2^k·p(r)` with `p` the Taylor polynomial of degree 13 (truncation
//! `< 4.3e-18` relative, below the round-off), evaluated by Estrin's scheme (five dependent
//! steps instead of Horner's fourteen: a query waits on this chain), `2^k` assembled in the
//! exponent bits. Measured against `f64::exp` over the range: ≤ 2 ulp. NaN propagates (`clamp`
//! keeps NaN; so does every step after it).
//!
//! Why not libm: `f64::exp` is an opaque call per unit; this form has no call and no branch, so
//! four units run through the SIMD lanes together.
//!
//! A unit can also be *moved* by a small step of its argument:
//! `e^{x+δ} = e^x·e^δ` with `e^δ` from its Taylor polynomial of degree 6, exact to round-off for
//! `|δ| ≤` [`SMALL_STEP_MAX`] (`0.01⁷/7! ≈ 2e-18`). Products of exponentials keep their relative
//! errors (no cancellation), so a moved unit is as accurate as a fresh one, up to one rounding
//! per move.
//!
//! Every kernel comes in two instantiations: `FMA = false` (a multiply then an add, any CPU) and
//! `FMA = true` (fused multiply–adds, for code compiled with the `fma` target feature, where
//! `mul_add` is one instruction). Both are exact to round-off; their last bits may differ.

// Indexed loops over fixed-size arrays on purpose: the vectoriser turns them into SIMD lanes,
// while array adaptors (`map`, `zip`) stayed out-of-line calls without the target features of
// the AVX2 instantiation.
#![allow(clippy::needless_range_loop)]

/// Largest step `|δ|` of a unit's `x = 2s` for which a move is exact to round-off.
pub const SMALL_STEP_MAX: f64 = 0.01;

/// Four hidden units (or four outputs), aligned for 256-bit loads.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
#[repr(C, align(32))]
pub struct Lane(pub [f64; 4]);

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

/// `1/n!` for n = 0 to 13.
const INV_FACT: [f64; 14] = [
    1.0,
    1.0,
    0.5,
    1.0 / 6.0,
    1.0 / 24.0,
    1.0 / 120.0,
    1.0 / 720.0,
    1.0 / 5_040.0,
    1.0 / 40_320.0,
    1.0 / 362_880.0,
    1.0 / 3_628_800.0,
    1.0 / 39_916_800.0,
    1.0 / 479_001_600.0,
    1.0 / 6_227_020_800.0,
];

/// `a·b + c`, fused when `FMA`.
#[inline(always)]
pub(super) fn madd<const FMA: bool>(a: f64, b: f64, c: f64) -> f64 {
    if FMA {
        a.mul_add(b, c)
    } else {
        a * b + c
    }
}

/// `e^x` for `x = 2s`, clamped as in the module doc (exact to ~2 ulp; NaN stays NaN).
#[inline(always)]
pub(super) fn exp_clamped<const FMA: bool>(x: f64) -> f64 {
    let x = x.clamp(-CLAMP_2S, CLAMP_2S);
    // k = round(x / ln 2), as a double and as the integer in the low bits of `kr`.
    let kr = x * std::f64::consts::LOG2_E + ROUND_MAGIC;
    let k = kr - ROUND_MAGIC;
    let r = (x - k * LN2_HI) - k * LN2_LO;
    let c = &INV_FACT;
    let r2 = r * r;
    let r4 = r2 * r2;
    let r8 = r4 * r4;
    let p01 = madd::<FMA>(c[1], r, c[0]);
    let p23 = madd::<FMA>(c[3], r, c[2]);
    let p45 = madd::<FMA>(c[5], r, c[4]);
    let p67 = madd::<FMA>(c[7], r, c[6]);
    let p89 = madd::<FMA>(c[9], r, c[8]);
    let p1011 = madd::<FMA>(c[11], r, c[10]);
    let p1213 = madd::<FMA>(c[13], r, c[12]);
    let q0 = madd::<FMA>(p23, r2, p01);
    let q1 = madd::<FMA>(p67, r2, p45);
    let q2 = madd::<FMA>(p1011, r2, p89);
    let s0 = madd::<FMA>(q1, r4, q0);
    let s1 = madd::<FMA>(p1213, r4, q2);
    let p = madd::<FMA>(s1, r8, s0);
    // 2^k: the biased exponent k + 1023 in the exponent field (|k| ≤ 58 after the clamp).
    let k_bits = kr.to_bits().wrapping_sub(ROUND_MAGIC.to_bits());
    let two_k = f64::from_bits(k_bits.wrapping_add(1023) << 52);
    p * two_k
}

/// `e^δ` for a small step `δ` by its Taylor polynomial of degree 6 (exact to round-off for
/// `|δ| ≤` [`SMALL_STEP_MAX`]), by Estrin's scheme.
#[inline(always)]
pub(super) fn exp_small<const FMA: bool>(d: f64) -> f64 {
    let c = &INV_FACT;
    let d2 = d * d;
    let d4 = d2 * d2;
    let p01 = madd::<FMA>(c[1], d, c[0]);
    let p23 = madd::<FMA>(c[3], d, c[2]);
    let p45 = madd::<FMA>(c[5], d, c[4]);
    let q0 = madd::<FMA>(p23, d2, p01);
    let q1 = madd::<FMA>(c[6], d2, p45);
    madd::<FMA>(q1, d4, q0)
}

/// `tanh(s)` from `e^{2s}`: `1 − 2/(e^{2s} + 1)`.
#[inline(always)]
pub(super) fn tanh_from_exp2s(e: f64) -> f64 {
    1.0 - 2.0 / (e + 1.0)
}

/// Whether every `|δ|` of a lane is at most [`SMALL_STEP_MAX`] (false for a NaN).
#[inline(always)]
pub(super) fn small_steps(d: [f64; 4]) -> bool {
    // `<=` is false for NaN, so a NaN never takes the polynomial.
    (d[0].abs() <= SMALL_STEP_MAX)
        & (d[1].abs() <= SMALL_STEP_MAX)
        & (d[2].abs() <= SMALL_STEP_MAX)
        & (d[3].abs() <= SMALL_STEP_MAX)
}

/// For each unit of `s`: `e = e^{2s}` and `a = tanh(s)` (slices of whole lanes, equal lengths;
/// portable code). The kernel alone, for tests and benches.
pub fn exp2_tanh_block(s: &[Lane], e: &mut [Lane], a: &mut [Lane]) {
    for ((s, e), a) in s.iter().zip(e.iter_mut()).zip(a.iter_mut()) {
        for u in 0..4 {
            e.0[u] = exp_clamped::<false>(2.0 * s.0[u]);
            a.0[u] = tanh_from_exp2s(e.0[u]);
        }
    }
}

/// Moves each unit from `s_old` (with `e = e^{2 s_old}`) to `s_new` when the lane's steps are
/// small (every `|δ| ≤` [`SMALL_STEP_MAX`]), afresh otherwise: `e ← e^{2 s_new}`,
/// `a ← tanh(s_new)` (portable code).
pub fn move_exp2_block(s_old: &[Lane], s_new: &[Lane], e: &mut [Lane], a: &mut [Lane]) {
    for (((so, sn), e), a) in s_old.iter().zip(s_new).zip(e.iter_mut()).zip(a.iter_mut()) {
        let mut d = [0.0; 4];
        for u in 0..4 {
            d[u] = 2.0 * (sn.0[u] - so.0[u]);
        }
        let small = small_steps(d);
        for u in 0..4 {
            e.0[u] = if small {
                e.0[u] * exp_small::<false>(d[u])
            } else {
                exp_clamped::<false>(2.0 * sn.0[u])
            };
            a.0[u] = tanh_from_exp2s(e.0[u]);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Distance in ulps between two finite doubles of the same sign.
    fn ulps(a: f64, b: f64) -> u64 {
        a.to_bits().abs_diff(b.to_bits())
    }

    #[test]
    fn the_exponential_is_within_two_ulp_of_libm_over_the_clamped_range() {
        // |2s| ≤ 40: the whole range before the clamp.
        for fma in [false, true] {
            let mut worst = 0;
            for i in -399_990..=399_990 {
                let s = f64::from(i) * 5e-5 + 1.234_567e-7;
                let got = if fma {
                    exp_clamped::<true>(2.0 * s)
                } else {
                    exp_clamped::<false>(2.0 * s)
                };
                worst = worst.max(ulps(got, (2.0 * s).exp()));
            }
            assert!(worst <= 2, "fma {fma}: worst {worst} ulp");
        }
        // The split rounds back to `LN_2`, the low part adds what `LN_2` lost.
        assert_eq!(LN2_HI + LN2_LO, std::f64::consts::LN_2);
        assert_ne!(LN2_LO, std::f64::consts::LN_2 - LN2_HI);
        assert_eq!(LN2_HI.to_bits() & 0xffff_ffff, 0);
    }

    #[test]
    fn tanh_saturates_exactly_where_the_query_path_does() {
        for s in [20.0, 20.5, 25.0, 1e3, 1e300, f64::INFINITY] {
            let libm = 1.0 - 2.0 / ((2.0 * s).exp() + 1.0);
            assert_eq!(tanh_from_exp2s(exp_clamped::<false>(2.0 * s)), libm, "{s}");
            assert_eq!(
                tanh_from_exp2s(exp_clamped::<false>(-2.0 * s)),
                -libm,
                "{s}"
            );
        }
        assert!(exp_clamped::<false>(f64::NAN).is_nan());
        assert!(tanh_from_exp2s(exp_clamped::<true>(f64::NAN)).is_nan());
    }

    #[test]
    fn tanh_is_the_query_paths_formula_to_round_off() {
        for i in -20_000..=20_000 {
            let s = f64::from(i) * 1e-3;
            let got = tanh_from_exp2s(exp_clamped::<false>(2.0 * s));
            // The library's query path: the same formula on libm's exponential.
            let libm = 1.0 - 2.0 / ((2.0 * s).exp() + 1.0);
            assert!((got - libm).abs() <= 4.5e-16, "{s}: {got} vs {libm}");
            assert!((got - s.tanh()).abs() < 1e-15, "{s}: {got} vs {}", s.tanh());
        }
    }

    fn lanes(v: impl Fn(usize) -> f64) -> Vec<Lane> {
        (0..4)
            .map(|l| Lane(std::array::from_fn(|u| v(4 * l + u))))
            .collect()
    }

    #[test]
    fn a_small_move_equals_a_fresh_evaluation_to_round_off() {
        let s_old = lanes(|j| -3.0 + 0.4 * j as f64);
        for step in [1e-9, -3e-6, 2e-4, -0.004, 0.0049] {
            let s_new = lanes(|j| -3.0 + 0.4 * j as f64 + step);
            let (mut e, mut a) = (vec![Lane::default(); 4], vec![Lane::default(); 4]);
            exp2_tanh_block(&s_old, &mut e, &mut a);
            move_exp2_block(&s_old, &s_new, &mut e, &mut a);
            for (l, lane) in s_new.iter().enumerate() {
                for (u, s) in lane.0.iter().enumerate() {
                    let want = (2.0 * s).exp();
                    assert!(ulps(e[l].0[u], want) <= 4, "{s}: {} vs {want}", e[l].0[u]);
                    assert!((a[l].0[u] - s.tanh()).abs() <= 4e-16, "{s}");
                }
            }
        }
    }

    #[test]
    fn the_small_step_polynomial_is_exp_to_round_off() {
        for fma in [false, true] {
            for i in -1000..=1000 {
                let d = f64::from(i) * 1e-5;
                let got = if fma {
                    exp_small::<true>(d)
                } else {
                    exp_small::<false>(d)
                };
                assert!(ulps(got, d.exp()) <= 1, "{d}: {got} vs {}", d.exp());
            }
        }
    }

    #[test]
    fn a_large_step_or_a_nan_takes_the_fresh_exponential() {
        assert!(small_steps([0.0, 0.01, -0.01, 1e-9]));
        assert!(!small_steps([0.0, 0.011, 0.0, 0.0]));
        assert!(!small_steps([0.0, 0.0, f64::NAN, 0.0]));
        let s_old = lanes(|j| j as f64 * 0.1);
        let s_new = lanes(|j| j as f64 * 0.1 + if j == 5 { 0.5 } else { 0.0 });
        let (mut e, mut a) = (vec![Lane::default(); 4], vec![Lane::default(); 4]);
        exp2_tanh_block(&s_old, &mut e, &mut a);
        move_exp2_block(&s_old, &s_new, &mut e, &mut a);
        let (mut e_fresh, mut a_fresh) = (e.clone(), a.clone());
        exp2_tanh_block(&s_new, &mut e_fresh, &mut a_fresh);
        // The lane with the large step is the fresh evaluation, to the bit.
        assert_eq!(e[1], e_fresh[1]);
        assert_eq!(a[1], a_fresh[1]);
    }
}
