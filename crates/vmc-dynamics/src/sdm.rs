//! First-order semi-discretisation (Insperger–Stépán) of periodic delay equations.
//!
//! Equation: ẋ(t) = A(t) x(t) + B(t) y(t − τ), y = C x, with A, B periodic of period T = τ
//! (in milling the delay is the tooth period). The period is split into m steps of
//! Δt = τ/m; on step i the coefficients are replaced by their means A_i, B_i and the
//! delayed output by the linear interpolation between y_{i−m} and y_{i−m+1} (first order).
//! The stored delayed samples are ordered oldest first: z_i = [x_i; y_{i−m}; …; y_{i−1}].
//! The exact solution of the resulting ODE over the step gives
//!
//! ```text
//! x_{i+1} = P_i x_i + R0_i y_{i−m} + R1_i y_{i−m+1}
//! P_i = e^{A_i Δt},  Φ0 = ∫₀^Δt e^{A_i(Δt−s)} ds B_i,  Φ1 = ∫₀^Δt e^{A_i(Δt−s)} s ds B_i / Δt
//! R0_i = Φ0 − Φ1,    R1_i = Φ1
//! ```
//!
//! all three read off one exponential of the block matrix [[A, B, 0], [0, 0, I], [0, 0, 0]]·Δt
//! (Van Loan). The discrete state z_i = [x_i; y_{i−1}; …; y_{i−m}] has dimension n + m·d and the
//! monodromy matrix Φ maps z_0 to z_m. Each step only writes the n rows of x and shifts the
//! delayed block, so Φ is built by propagating the n × (n + m d) row block X_j = ∂x_j/∂z_0
//! (cost ≈ m·n²·(n + m d)/2, see [`monodromy_from`]) instead of multiplying m dense step
//! matrices. The system is
//! asymptotically stable when the spectral radius of Φ is below 1. Columns of Φ that are
//! identically zero (delayed samples that no step reads, e.g. while no tooth cuts) only add
//! zero multipliers and are removed before the eigenvalue computation.
//!
//! The error of the first-order method decreases as O(m⁻²) (see the convergence test).

use std::f64::consts::PI;

use nalgebra::{Complex, DMatrix};
use serde::{Deserialize, Serialize};

/// How stability is lost when the critical multiplier leaves the unit circle.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum BoundaryKind {
    /// Secondary Hopf (Neimark–Sacker): a complex pair of multipliers.
    Hopf,
    /// Period doubling: a real multiplier at −1.
    Flip,
}

/// One point of a stability-lobe diagram.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct LobePoint {
    /// Spindle speed in rpm.
    pub spindle_rpm: f64,
    /// Critical axial depth in mm.
    pub critical_depth_mm: f64,
    /// Chatter frequency in Hz.
    pub chatter_frequency_hz: f64,
    /// How stability is lost.
    pub kind: BoundaryKind,
    /// Steps per tooth period of the discretisation behind the point: for the
    /// semi-discretisation the finest one (with the converged rule of [`crate::converged`] the
    /// depth is extrapolated from it and the resolution of half as many steps), for the time
    /// domain its RK4 steps per tooth period; `None` for the zero-order solution, which has no
    /// time steps. Files written before it existed read as `None`.
    #[serde(default)]
    pub steps_per_period: Option<usize>,
}

/// Discrete map of one semi-discretisation step.
#[derive(Debug, Clone, PartialEq)]
pub struct Step {
    /// State transition P = e^{AΔt} (n × n).
    pub p: DMatrix<f64>,
    /// Delayed-input matrices (R0, R1), each n × d; `None` when B = 0 on this step.
    pub r: Option<(DMatrix<f64>, DMatrix<f64>)>,
}

impl Step {
    /// Step with mean coefficients `a` (n × n), `b` (n × d) over a step `dt_s` long.
    pub fn new(a: &DMatrix<f64>, b: &DMatrix<f64>, dt_s: f64) -> Self {
        let n = a.nrows();
        let d = b.ncols();
        if b.iter().all(|v| *v == 0.0) {
            return Self::free(a, dt_s);
        }
        let size = n + 2 * d;
        let mut big = DMatrix::zeros(size, size);
        big.view_mut((0, 0), (n, n)).copy_from(&(a * dt_s));
        big.view_mut((0, n), (n, d)).copy_from(&(b * dt_s));
        for k in 0..d {
            // Unscaled: M = [[A, B, 0], [0, 0, I/Δt], [0, 0, 0]], so M·Δt carries I here.
            big[(n + k, n + d + k)] = 1.0;
        }
        let e = big.exp();
        let p = e.view((0, 0), (n, n)).into_owned();
        let phi0 = e.view((0, n), (n, d)).into_owned();
        // The (1,3) block is ∫₀^Δt e^{A(Δt−s)} B (s/Δt) ds (Van Loan).
        let phi1 = e.view((0, n + d), (n, d)).into_owned();
        Self {
            p,
            r: Some((&phi0 - &phi1, phi1)),
        }
    }

    /// Step without delayed input (B = 0): only P = e^{AΔt}.
    pub fn free(a: &DMatrix<f64>, dt_s: f64) -> Self {
        Self {
            p: (a * dt_s).exp(),
            r: None,
        }
    }
}

/// Borrowed view of a [`Step`], so that identical steps can share one matrix.
#[derive(Debug, Clone, Copy)]
pub struct StepRef<'a> {
    /// State transition P (n × n).
    pub p: &'a DMatrix<f64>,
    /// Delayed-input matrices (R0, R1), each n × d.
    pub r: Option<(&'a DMatrix<f64>, &'a DMatrix<f64>)>,
}

impl Step {
    /// Borrowed view.
    pub fn as_ref(&self) -> StepRef<'_> {
        StepRef {
            p: &self.p,
            r: self.r.as_ref().map(|(a, b)| (a, b)),
        }
    }
}

/// Monodromy matrix over one period from the m steps and the output matrix C (d × n).
pub fn monodromy(steps: &[Step], c: &DMatrix<f64>) -> DMatrix<f64> {
    let refs: Vec<StepRef<'_>> = steps.iter().map(Step::as_ref).collect();
    monodromy_from(&refs, c)
}

/// Monodromy matrix from borrowed steps. The discrete state is ordered
/// z_i = [x_i; y_{i−m}; y_{i−m+1}; …; y_{i−1}], so step j reads delayed blocks j and j + 1 and
/// the row block X_j = ∂x_j/∂z_0 is zero beyond its first n + (j + 1)·d columns.
/// Delayed samples that no step reads have zero columns (and their rows are not needed): the
/// full matrix is [`monodromy_compact`]'s with those rows and columns put back as zeros.
pub fn monodromy_from(steps: &[StepRef<'_>], c: &DMatrix<f64>) -> DMatrix<f64> {
    let (n, d) = (c.ncols(), c.nrows());
    let big_n = n + steps.len() * d;
    let (compact, blocks) = monodromy_compact(steps, c);
    let index = |i: usize| {
        if i < n {
            i
        } else {
            n + blocks[(i - n) / d] * d + (i - n) % d
        }
    };
    let mut phi = DMatrix::zeros(big_n, big_n);
    for j in 0..compact.ncols() {
        for i in 0..compact.nrows() {
            phi[(index(i), index(j))] = compact[(i, j)];
        }
    }
    phi
}

/// The monodromy matrix restricted to the states that matter: x and the delayed samples some
/// step reads (in milling at small radial immersion, those of the few steps in which a tooth
/// cuts), with the indices of those delayed blocks. Same eigenvalues as the full matrix but
/// for zeros.
///
/// Each step multiplies only the nonzero prefix of the row block X_j = ∂x_j/∂z_0 (no dense
/// products of (n + m d)-square step matrices), and a run of free steps (no delayed input)
/// that share one transition matrix P and whose outputs nothing reads is taken in one
/// product with P^L (L the run's length, by repeated squaring).
pub fn monodromy_compact(steps: &[StepRef<'_>], c: &DMatrix<f64>) -> (DMatrix<f64>, Vec<usize>) {
    let m = steps.len();
    let d = c.nrows();
    let n = c.ncols();
    // Block k of z (= y_{k−m} at the start, y_k at the end) is read by step k (R0) or step
    // k − 1 (R1).
    let read = |k: usize| steps[k].r.is_some() || (k > 0 && steps[k - 1].r.is_some());
    let blocks: Vec<usize> = (0..m).filter(|&k| read(k)).collect();
    let mut slot = vec![usize::MAX; m];
    for (i, &k) in blocks.iter().enumerate() {
        slot[k] = i;
    }
    // Kept blocks with index ≤ j, for j = 0 … m − 1.
    let mut kept_upto = vec![0; m];
    let mut count = 0;
    for (j, kept) in kept_upto.iter_mut().enumerate() {
        if slot[j] != usize::MAX {
            count += 1;
        }
        *kept = count;
    }
    let size = n + blocks.len() * d;
    let mut x = DMatrix::zeros(n, size);
    x.view_mut((0, 0), (n, n)).fill_with_identity();
    let mut next = DMatrix::zeros(n, size);
    let mut phi = DMatrix::zeros(size, size);
    let mut powers: Vec<(*const DMatrix<f64>, usize, DMatrix<f64>)> = Vec::new();
    let mut j = 0;
    while j < m {
        let step = steps[j];
        let width = n + kept_upto[j] * d;
        if slot[j] != usize::MAX {
            // y_j = C x_j is block j of z_m.
            phi.view_mut((n + slot[j] * d, 0), (d, width))
                .gemm(1.0, c, &x.columns(0, width), 0.0);
        }
        let mut len = 1;
        if step.r.is_none() {
            while j + len < m
                && steps[j + len].r.is_none()
                && std::ptr::eq(steps[j + len].p, step.p)
                && !read(j + len)
            {
                len += 1;
            }
        }
        let p: &DMatrix<f64> = if len == 1 {
            step.p
        } else {
            let key = step.p as *const DMatrix<f64>;
            let at = match powers.iter().position(|(k, l, _)| *k == key && *l == len) {
                Some(at) => at,
                None => {
                    powers.push((key, len, matrix_power(step.p, len)));
                    powers.len() - 1
                }
            };
            &powers[at].2
        };
        next.columns_mut(0, width)
            .gemm(1.0, p, &x.columns(0, width), 0.0);
        if let Some((r0, r1)) = step.r {
            // y_{j−m} is block j of z_0 (kept: step j reads it).
            let mut b0 = next.view_mut((0, n + slot[j] * d), (n, d));
            b0 += r0;
            if j + 1 < m {
                // y_{j−m+1} is block j + 1 of z_0 (its columns are still zero in `next`).
                let mut b1 = next.view_mut((0, n + slot[j + 1] * d), (n, d));
                b1 += r1;
            } else {
                // y_0 = C x_0 with x_0 the first n entries of z_0.
                next.view_mut((0, 0), (n, n)).gemm(1.0, r1, c, 1.0);
            }
        }
        std::mem::swap(&mut x, &mut next);
        j += len;
    }
    phi.view_mut((0, 0), (n, size)).copy_from(&x);
    (phi, blocks)
}

/// P^k (k ≥ 1) by repeated squaring: P · P^(k−1).
fn matrix_power(p: &DMatrix<f64>, k: usize) -> DMatrix<f64> {
    let mut out = p.clone();
    let mut base = p.clone();
    let mut rest = k.saturating_sub(1);
    while rest > 0 {
        if rest & 1 == 1 {
            out = &out * &base;
        }
        rest >>= 1;
        if rest > 0 {
            base = &base * &base;
        }
    }
    out
}

/// Φ without its zero columns (and their rows), which carry only zero multipliers; `None`
/// when every column is zero.
fn reduced(phi: &DMatrix<f64>) -> Option<DMatrix<f64>> {
    let rows = phi.nrows();
    let keep: Vec<usize> = phi
        .as_slice()
        .chunks_exact(rows)
        .enumerate()
        .filter(|(_, col)| col.iter().any(|v| *v != 0.0))
        .map(|(j, _)| j)
        .collect();
    if keep.is_empty() {
        return None;
    }
    let k = keep.len();
    Some(DMatrix::from_fn(k, k, |i, j| phi[(keep[i], keep[j])]))
}

/// Eigenvalues of Φ after removing the zero columns (and their rows), which carry only zero
/// multipliers (full decomposition).
pub fn multipliers(phi: &DMatrix<f64>) -> Vec<Complex<f64>> {
    match reduced(phi) {
        None => vec![Complex::new(0.0, 0.0)],
        Some(r) if r.nrows() == 1 => vec![Complex::new(r[(0, 0)], 0.0)],
        Some(r) => r.complex_eigenvalues().iter().copied().collect(),
    }
}

/// Reduced monodromy matrices from this size on try the Arnoldi method of
/// [`crate::arnoldi`] before the full decomposition.
pub const ARNOLDI_FROM: usize = 120;

/// The multiplier of largest modulus (ties resolved towards positive imaginary part): by
/// Arnoldi for a reduced matrix of [`ARNOLDI_FROM`] states or more when it converges, else
/// from the full decomposition.
pub fn critical_multiplier(phi: &DMatrix<f64>) -> Complex<f64> {
    if let Some(r) = reduced(phi).filter(|r| r.nrows() >= ARNOLDI_FROM) {
        if let Some(mu) = crate::arnoldi::dominant_eigenvalue(&r) {
            return mu;
        }
    }
    largest(&multipliers(phi))
}

/// The largest-modulus value of a list (ties towards positive imaginary part); it lives with
/// the Arnoldi iteration, which picks its Ritz values by the same rule.
pub use crate::arnoldi::largest;

/// Classifies a critical multiplier: real and negative is a flip, anything else a Hopf pair.
pub fn classify(mu: Complex<f64>) -> BoundaryKind {
    if mu.re < 0.0 && mu.im.abs() <= 1e-9 * mu.norm() {
        BoundaryKind::Flip
    } else {
        BoundaryKind::Hopf
    }
}

/// Chatter frequency in Hz from a multiplier μ = e^{iωτ}: among (±arg μ/2π + k)/τ, the one
/// closest to one of the reference (natural) frequencies.
pub fn chatter_frequency_hz(mu: Complex<f64>, period_s: f64, reference_hz: &[f64]) -> f64 {
    let theta = mu.arg().abs() / (2.0 * PI);
    let tooth_hz = 1.0 / period_s;
    let mut best = theta * tooth_hz;
    let mut best_err = f64::INFINITY;
    for &f_ref in reference_hz {
        let k = (f_ref / tooth_hz).floor();
        for cand in [k - theta, k + theta, k + 1.0 - theta, k + 1.0 + theta] {
            let f = cand * tooth_hz;
            if f > 0.0 && (f - f_ref).abs() < best_err {
                best_err = (f - f_ref).abs();
                best = f;
            }
        }
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Spectral radius of the delayed damped Mathieu equation
    /// ẍ + a1 ẋ + (δ + ε cos t) x = b0 x(t − 2π), period and delay 2π, m steps.
    fn mathieu_radius(delta: f64, eps: f64, b0: f64, a1: f64, m: usize) -> f64 {
        let t = 2.0 * PI;
        let dt = t / m as f64;
        let c = DMatrix::from_row_slice(1, 2, &[1.0, 0.0]);
        let b = DMatrix::from_row_slice(2, 1, &[0.0, b0]);
        let steps: Vec<Step> = (0..m)
            .map(|i| {
                // Mean of cos t over the step, exactly.
                let (ta, tb) = (i as f64 * dt, (i + 1) as f64 * dt);
                let mean_cos = (tb.sin() - ta.sin()) / dt;
                let a = DMatrix::from_row_slice(2, 2, &[0.0, 1.0, -delta - eps * mean_cos, -a1]);
                Step::new(&a, &b, dt)
            })
            .collect();
        critical_multiplier(&monodromy(&steps, &c)).norm()
    }

    fn hayes_multiplier(a: f64, b: f64, m: usize) -> Complex<f64> {
        let dt = 1.0 / m as f64;
        let am = DMatrix::from_element(1, 1, a);
        let bm = DMatrix::from_element(1, 1, b);
        let steps: Vec<Step> = (0..m).map(|_| Step::new(&am, &bm, dt)).collect();
        critical_multiplier(&monodromy(&steps, &DMatrix::identity(1, 1)))
    }

    /// Regression value of SemiDiscretizationMethod.jl (test/runtests.jl, delay Mathieu
    /// example δ = 3, ε = 2, b0 = −0.15, a1 = 0.1, T = τ = 2π, first order, Δt = 0.01):
    /// ρ = 0.5131596340374617. That package maps n_steps = 628 steps of 0.01, i.e. 6.28 instead
    /// of 2π, with a delay that is not a whole number of steps; here Δt = 2π/628 exactly, whose
    /// limit m → ∞ is ρ = 0.512052. The two agree to 0.3 % (1.5e-3 absolute); the converged
    /// value of this implementation is pinned to 1e-5.
    #[test]
    fn delayed_mathieu_matches_semidiscretizationmethod_jl() {
        let rho = mathieu_radius(3.0, 2.0, -0.15, 0.1, 628);
        assert!(
            (rho - 0.513_159_634_037_461_7).abs() < 1.5e-3,
            "rho = {rho}"
        );
        assert!((rho - 0.512_052).abs() < 1e-5, "rho = {rho}");
    }

    /// Hayes equation ẋ = a x + b x(t − 1): its exact border (the chart of
    /// SemiDiscretizationMethod.jl's README) is b = −a on the real branch and, on the Hopf
    /// branch, a = ω cot ω, b = −ω / sin ω (ω ∈ (0, π)); e.g. a = 0 gives b = −π/2.
    #[test]
    fn hayes_borders() {
        for &w in &[0.5_f64, PI / 2.0, 2.0, 2.5] {
            let a = w / w.tan();
            let b_crit = -w / w.sin();
            let inside = hayes_multiplier(a, 0.99 * b_crit, 50);
            let outside = hayes_multiplier(a, 1.01 * b_crit, 50);
            assert!(inside.norm() < 1.0 && outside.norm() > 1.0, "w = {w}");
            assert_eq!(classify(outside), BoundaryKind::Hopf);
            // Bisection on b recovers the border to O(m⁻²).
            let (mut lo, mut hi) = (0.9 * b_crit, 1.1 * b_crit);
            for _ in 0..40 {
                let mid = 0.5 * (lo + hi);
                if hayes_multiplier(a, mid, 50).norm() < 1.0 {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            assert!(
                (lo / b_crit - 1.0).abs() < 1e-3,
                "w = {w}: {lo} vs {b_crit}"
            );
        }
        // Real branch b = −a with a < 0 … 1: at a = −0.5 the border is b = 0.5, multiplier +1.
        let mu_in = hayes_multiplier(-0.5, 0.49, 40);
        let mu_out = hayes_multiplier(-0.5, 0.51, 40);
        assert!(mu_in.norm() < 1.0 && mu_out.norm() > 1.0);
        assert!(mu_out.re > 0.0 && mu_out.im.abs() < 1e-12);
    }

    /// Observed order of convergence of ρ in m on the delayed Mathieu equation: errors
    /// 4.6e-3, 1.18e-3, 2.9e-4 for m = 20, 40, 80 against m = 640, i.e. order 1.97 and 2.01.
    #[test]
    fn convergence_is_second_order() {
        let reference = mathieu_radius(3.0, 2.0, -0.15, 0.1, 640);
        let errs: Vec<f64> = [20, 40, 80]
            .iter()
            .map(|&m| (mathieu_radius(3.0, 2.0, -0.15, 0.1, m) - reference).abs())
            .collect();
        println!("Mathieu |ρ_m − ρ_640| for m = 20, 40, 80: {errs:?}");
        for w in errs.windows(2) {
            let order = (w[0] / w[1]).log2();
            assert!(
                (1.8..2.3).contains(&order),
                "order {order}, errors {errs:?}"
            );
        }
    }

    /// The full (n + m d)-square matrix of one step: x ← P x + R0 y_{i−m} + R1 y_{i−m+1}, the
    /// delayed blocks shift by one and the newest is C x.
    fn dense_step(step: StepRef<'_>, c: &DMatrix<f64>, m: usize) -> DMatrix<f64> {
        let (n, d) = (c.ncols(), c.nrows());
        let big = n + m * d;
        let mut s = DMatrix::zeros(big, big);
        s.view_mut((0, 0), (n, n)).copy_from(step.p);
        if let Some((r0, r1)) = step.r {
            s.view_mut((0, n), (n, d)).copy_from(r0);
            s.view_mut((0, n + d), (n, d)).copy_from(r1);
        }
        for k in 0..m - 1 {
            for r in 0..d {
                s[(n + k * d + r, n + (k + 1) * d + r)] = 1.0;
            }
        }
        s.view_mut((n + (m - 1) * d, 0), (d, n)).copy_from(c);
        s
    }

    /// The monodromy matrix (free runs taken as powers, only the read delayed samples kept)
    /// equals the product of the dense step matrices, and the compact matrix has the same
    /// nonzero multipliers, on a period of 14 steps: a free run, three cutting steps with
    /// different coefficients, a longer free run, two cutting steps at the end.
    #[test]
    fn monodromy_equals_the_dense_product_of_its_steps() {
        let (m, dt) = (14, 0.05);
        let c = DMatrix::from_row_slice(1, 2, &[1.0, 0.0]);
        let b = DMatrix::from_row_slice(2, 1, &[0.0, -0.4]);
        let free = Step::free(&DMatrix::from_row_slice(2, 2, &[0.0, 1.0, -4.0, -0.2]), dt);
        let cut: Vec<Step> = (0..5)
            .map(|i| {
                let k = 4.0 + 0.7 * i as f64;
                let a = DMatrix::from_row_slice(2, 2, &[0.0, 1.0, -k, -0.2]);
                Step::new(&a, &(&b * (1.0 + 0.1 * i as f64)), dt)
            })
            .collect();
        let pattern = [0, 0, 0, 1, 2, 3, 0, 0, 0, 0, 0, 0, 4, 5];
        let refs: Vec<StepRef<'_>> = pattern
            .iter()
            .map(|&k| {
                if k == 0 {
                    free.as_ref()
                } else {
                    cut[k - 1].as_ref()
                }
            })
            .collect();
        let mut dense = DMatrix::identity(2 + m, 2 + m);
        for s in &refs {
            dense = dense_step(*s, &c, m) * dense;
        }
        let phi = monodromy_from(&refs, &c);
        // Columns of delayed samples that no step reads are zero in Φ, not in the dense product
        // (they feed rows that nothing reads); compare the columns that are read.
        let (compact, blocks) = monodromy_compact(&refs, &c);
        assert_eq!(blocks, vec![3, 4, 5, 6, 12, 13]);
        let keep: Vec<usize> = (0..2).chain(blocks.iter().map(|k| 2 + k)).collect();
        for &j in &keep {
            for &i in &keep {
                assert!(
                    (phi[(i, j)] - dense[(i, j)]).abs() < 1e-12,
                    "({i}, {j}): {} vs {}",
                    phi[(i, j)],
                    dense[(i, j)]
                );
            }
        }
        let mut full: Vec<f64> = dense
            .complex_eigenvalues()
            .iter()
            .map(|l| l.norm())
            .collect();
        let mut small: Vec<f64> = multipliers(&compact).iter().map(|l| l.norm()).collect();
        full.sort_by(|a, b| b.total_cmp(a));
        small.sort_by(|a, b| b.total_cmp(a));
        for (a, b) in full.iter().zip(&small) {
            assert!((a - b).abs() < 1e-10, "{full:?} vs {small:?}");
        }
        assert!(full[small.len()..].iter().all(|v| *v < 1e-10), "{full:?}");
    }

    #[test]
    fn chatter_frequency_picks_the_alias_near_the_mode() {
        // μ = e^{iθ}, θ = 0.3·2π, τ = 1 ms: candidates (k ± 0.3)·1000 Hz; 700 Hz is nearest 930 Hz.
        let mu = Complex::from_polar(1.0, 0.3 * 2.0 * PI);
        let f = chatter_frequency_hz(mu, 1e-3, &[930.0]);
        assert!((f - 700.0).abs() < 1e-9);
    }
}
