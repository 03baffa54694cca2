//! The query stage of the compiled model: the axis parts at a position, the first-order
//! synthesis and the fixed point of the compensation (module doc of `compiled`).
//!
//! One axis part at position `q` (mm): per hidden unit `x_j = 2s_j = c₂_j + w₂_j·q` with
//! `w₂ = 2w/σ_q` (the position's normalisation folded into the weight) and
//! `c₂ = 2c − w₂·m` (cached per readings), `a_j = tanh(s_j) = 1 − 2/(e^{x_j} + 1)`; the outputs
//! `y_o = (b2_o + Σ_j V_oj·a_j)·σ'_o + μ'_o + (l'_o·q + l_o)`, where `σ'`, `μ'`, `l`, `l'` carry the
//! synthesis's unit (µm → mm, µrad → rad) and the sign of the axis's side of the chain, so the
//! six outputs are the signed translations (mm) and rotations (rad) the synthesis sums:
//! `E = Σ_k [δ'_k + ε'_k × (T + M_k⊙q)] + C + (−q_y·α_xy + q_z·α_xz, −q_z·α_yz, 0)`, with `C` the
//! spindle's drifts and tilts at the tool (cached per readings and tool).
//!
//! A moved evaluation (the fixed point's later iterates) steps each unit's `x` by `w₂·Δq`.
//! Every fold is one rounding more than the library's arithmetic: the difference stays at
//! round-off (tested to 1e-15 mm).
//!
//! Each evaluation runs in two passes over the blocks of four units — the activations, then the
//! output sums (fused, the six sums and the exponential's constants outgrow the registers and
//! the vectoriser splits the lanes) — and the code is instantiated twice ([`Isa`]): portable
//! (SSE2 on x86-64: two lanes, a multiply then an add) and, where the CPU has them (detected
//! when the model is built), AVX2 with fused multiply–adds (four lanes).

// Indexed loops over fixed-size arrays on purpose: the vectoriser turns them into SIMD lanes,
// while array adaptors (`map`, `zip`) stayed out-of-line calls without the target features of
// the AVX2 instantiation.
#![allow(clippy::needless_range_loop)]

use crate::controller::{fixed_point_mm, reversal_mm, SolveInfo};

use super::kernel::{exp_clamped, exp_small, madd, small_steps, tanh_from_exp2s};
use super::CompiledHybrid;

/// Outputs of an axis part: δx, δy, δz (µm), εx, εy, εz (µrad).
pub(super) const N_OUT: usize = 6;

/// The outputs padded to two lanes of four.
pub(super) const OUT_PAD: usize = 8;

/// Which instantiation of the query code runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Isa {
    /// Any CPU of the target.
    Portable,
    /// x86-64 with AVX2 and FMA.
    #[cfg_attr(not(target_arch = "x86_64"), allow(dead_code))]
    Avx2Fma,
}

impl Isa {
    /// The best the running CPU has.
    pub fn detect() -> Self {
        #[cfg(target_arch = "x86_64")]
        {
            if std::arch::is_x86_feature_detected!("avx2")
                && std::arch::is_x86_feature_detected!("fma")
            {
                return Isa::Avx2Fma;
            }
        }
        Isa::Portable
    }
}

/// What an axis part's query reads beside its units, per output (δx, δy, δz, εx, εy, εz): the
/// output layer's biases and de-normalisation and the linear part's terms, all but the biases
/// in signed mm and rad (module doc); the position's normalisation; the last position.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
#[repr(C, align(32))]
pub(super) struct AxisHead {
    /// Output biases `b2` (normalised units).
    pub b2: [f64; N_OUT],
    /// `σ'_o`: output standard deviations × unit × side sign.
    pub out_std: [f64; N_OUT],
    /// `μ'_o`: output means × unit × side sign.
    pub out_mean: [f64; N_OUT],
    /// `l_o`: the linear part's intercept with the temperature terms × unit × sign (per
    /// readings).
    pub lin_const: [f64; N_OUT],
    /// `l'_o`: the linear part's position slope with the bilinear products × unit × sign (per
    /// readings).
    pub lin_pos: [f64; N_OUT],
    /// Unit × side sign of each output (µm → mm, µrad → rad; ±1).
    pub out_scale: [f64; N_OUT],
    /// Position normalisation `[m, σ_q]` (mm).
    pub pos_norm: [f64; 2],
    /// Position of the last evaluation (mm).
    pub last_q_mm: f64,
    /// Position of the fresh evaluation that started the last solve (mm), valid for the held
    /// readings and code when `start_valid`: a solve starting at the same coordinate reuses it.
    pub start_q_mm: f64,
    /// Whether `start_q_mm`, `start_out` and the blocks' `e_start` hold an evaluation.
    pub start_valid: bool,
    /// The outputs of the fresh evaluation at `start_q_mm`.
    pub start_out: [f64; N_OUT],
    /// Hidden units of the part's net (0: linear part only).
    pub hidden: usize,
    /// Its units are `units[start..start + blocks]` of the model's blocks.
    pub start: usize,
    /// Blocks of four units.
    pub blocks: usize,
}

/// Four hidden units of an axis part and everything a query does with them (352 bytes).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
#[repr(C, align(32))]
pub(super) struct UnitBlock {
    /// `w₂ = 2w/σ_q`: the first-layer weight of the position, normalisation folded in.
    pub w2: [f64; 4],
    /// `c₂ = 2c − w₂·m` for the held readings.
    pub c2: [f64; 4],
    /// `e^{x_j}` of the last evaluation.
    pub e: [f64; 4],
    /// `e^{x_j}` of the fresh evaluation at the head's `start_q_mm`.
    pub e_start: [f64; 4],
    /// Activations `tanh(s_j)` of the last evaluation.
    pub a: [f64; 4],
    /// Output weights `V_oj`, unit-major and padded to eight outputs (`v[u][o]`, zero for
    /// `o ≥ 6`): a unit's contribution to the outputs is two 4-wide multiply–adds.
    pub v: [[f64; OUT_PAD]; 4],
}

/// The part's six outputs (signed mm and rad) for position `q_mm`; `MOVE`: every block whose
/// steps are small moved from the last evaluation, the others afresh; else all afresh.
///
/// The output layer sums per output in two partial sums (unit `j` into sum `j mod 2`) added
/// at the end, then the bias: another order than the library's running sum from the bias, a
/// difference of round-off (~1e-16 of the normalised output).
#[inline(always)]
fn axis_eval<const FMA: bool, const MOVE: bool>(
    head: &mut AxisHead,
    units: &mut [UnitBlock],
    q_mm: f64,
) -> [f64; N_OUT] {
    let dq = q_mm - head.last_q_mm;
    head.last_q_mm = q_mm;
    for b in units.iter_mut() {
        // Plain fixed-size loops only: an array adaptor (`map`) is an out-of-line call that
        // would not get the instantiation's target features.
        let mut e_new = [0.0; 4];
        let mut moved = false;
        if MOVE {
            let mut d = [0.0; 4];
            for u in 0..4 {
                d[u] = b.w2[u] * dq;
            }
            if small_steps(d) {
                for u in 0..4 {
                    e_new[u] = b.e[u] * exp_small::<FMA>(d[u]);
                }
                moved = true;
            }
        }
        if !moved {
            for u in 0..4 {
                e_new[u] = exp_clamped::<FMA>(madd::<FMA>(b.w2[u], q_mm, b.c2[u]));
            }
        }
        b.e = e_new;
    }
    activations(units);
    output_sums::<FMA>(head, units, q_mm)
}

/// `a_j = tanh(s_j) = 1 − 2/(e_j + 1)` of every unit from its `e_j = e^{2s_j}` (one 4-wide
/// division per block; sharing one division among several blocks by products of `e_j + 1`
/// cost more instructions and time than it saved, see the decision record).
#[inline(always)]
fn activations(units: &mut [UnitBlock]) {
    for b in units.iter_mut() {
        for u in 0..4 {
            b.a[u] = tanh_from_exp2s(b.e[u]);
        }
    }
}

/// The six outputs from the activations held in `units` (first pass done).
#[inline(always)]
fn output_sums<const FMA: bool>(head: &AxisHead, units: &[UnitBlock], q_mm: f64) -> [f64; N_OUT] {
    // Two sets of sums (even and odd units) halve the chain of dependent multiply–adds.
    let mut acc = [[0.0; OUT_PAD]; 2];
    for b in units.iter() {
        for u in 0..4 {
            for o in 0..OUT_PAD {
                acc[u % 2][o] = madd::<FMA>(b.v[u][o], b.a[u], acc[u % 2][o]);
            }
        }
    }
    let mut out = [0.0; N_OUT];
    for o in 0..N_OUT {
        let sum = head.b2[o] + (acc[0][o] + acc[1][o]);
        let y = madd::<FMA>(sum, head.out_std[o], head.out_mean[o]);
        out[o] = y + madd::<FMA>(head.lin_pos[o], q_mm, head.lin_const[o]);
    }
    out
}

impl CompiledHybrid {
    /// The first-order synthesis of the axis parts' signed outputs `v` (mm, rad) at `q_mm`
    /// (module doc), with the cached spindle and squareness.
    #[inline(always)]
    fn synthesise_mm(&self, q_mm: [f64; 3], v: &[[f64; N_OUT]; 3]) -> [f64; 3] {
        let g = &self.synthesis;
        let t = g.tool_offset_mm;
        let q = q_mm;
        let mut per_axis = [[0.0; 3]; 3];
        for (k, pa) in per_axis.iter_mut().enumerate() {
            let m = &g.arm_mask[k];
            let arm = [t[0] + m[0] * q[0], t[1] + m[1] * q[1], t[2] + m[2] * q[2]];
            let abbe = cross([v[k][3], v[k][4], v[k][5]], arm);
            for i in 0..3 {
                pa[i] = v[k][i] + abbe[i];
            }
        }
        let c = self.constant_mm;
        let [yz, xz, xy] = self.squareness_rad;
        let sq = [q[2] * xz - q[1] * xy, -(q[2] * yz), 0.0];
        std::array::from_fn(|i| {
            (per_axis[0][i] + per_axis[1][i]) + (per_axis[2][i] + (c[i] + sq[i]))
        })
    }

    /// `E(q)` (mm), the readings stage done; `MOVE` as [`axis_eval`].
    #[inline(always)]
    fn error_mm<const FMA: bool, const MOVE: bool>(&mut self, q_mm: [f64; 3]) -> [f64; 3] {
        let mut v = [[0.0; N_OUT]; 3];
        for (k, v) in v.iter_mut().enumerate() {
            let head = &mut self.heads[k];
            let units = &mut self.units[head.start..head.start + head.blocks];
            *v = axis_eval::<FMA, MOVE>(head, units, q_mm[k]);
        }
        self.synthesise_mm(q_mm, &v)
    }

    /// `E(q)` (mm) for the first iterate of a solve, `q` the commanded position: fresh, but an
    /// axis part whose coordinate is bit-for-bit the one its last solve started at (held
    /// readings) takes that evaluation's outputs and exponentials, which a fresh evaluation
    /// would repeat to the bit (an axis at rest: most servo periods of a contour leave one
    /// or two axes still).
    #[inline(always)]
    fn error_start_mm<const FMA: bool>(&mut self, q_mm: [f64; 3]) -> [f64; 3] {
        let mut v = [[0.0; N_OUT]; 3];
        for (k, v) in v.iter_mut().enumerate() {
            let head = &mut self.heads[k];
            let units = &mut self.units[head.start..head.start + head.blocks];
            if head.start_valid && q_mm[k].to_bits() == head.start_q_mm.to_bits() {
                for b in units.iter_mut() {
                    b.e = b.e_start;
                }
                head.last_q_mm = q_mm[k];
                *v = head.start_out;
            } else {
                *v = axis_eval::<FMA, false>(head, units, q_mm[k]);
                for b in units.iter_mut() {
                    b.e_start = b.e;
                }
                head.start_q_mm = q_mm[k];
                head.start_out = *v;
                head.start_valid = true;
            }
        }
        self.synthesise_mm(q_mm, &v)
    }

    /// The fixed point (see [`Self::solve_mm`], the library's loop): the first evaluation fresh
    /// (or kept, [`Self::error_start_mm`]), the later ones moved from the previous iterate.
    #[inline(always)]
    fn solve_with<const FMA: bool>(
        &mut self,
        p_mm: [f64; 3],
        reversal_mm: [f64; 3],
        tol_mm: f64,
        max_iterations: usize,
    ) -> ([f64; 3], SolveInfo) {
        fixed_point_mm(p_mm, reversal_mm, tol_mm, max_iterations, |i, q| {
            if i == 0 {
                self.error_start_mm::<FMA>(q)
            } else {
                self.error_mm::<FMA, true>(q)
            }
        })
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma")]
    fn solve_avx2(
        &mut self,
        p_mm: [f64; 3],
        reversal_mm: [f64; 3],
        tol_mm: f64,
        max_iterations: usize,
    ) -> ([f64; 3], SolveInfo) {
        self.solve_with::<true>(p_mm, reversal_mm, tol_mm, max_iterations)
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma")]
    fn error_fresh_avx2(&mut self, q_mm: [f64; 3]) -> [f64; 3] {
        self.error_mm::<true, false>(q_mm)
    }

    /// `E(q)` (mm) with every activation fresh, readings stage first if due.
    pub(super) fn error_fresh_mm(&mut self, q_mm: [f64; 3]) -> [f64; 3] {
        if self.stale {
            self.update_temps();
        }
        match self.isa {
            // SAFETY: `Isa::Avx2Fma` is chosen only when the CPU reports AVX2 and FMA.
            #[cfg(target_arch = "x86_64")]
            Isa::Avx2Fma => unsafe { self.error_fresh_avx2(q_mm) },
            _ => self.error_mm::<false, false>(q_mm),
        }
    }

    /// The compensation's fixed point for the commanded position `p_mm` (mm), with the
    /// reversal of the axes flagged in `negative`: `q₀ = p`, `q_{i+1} = p − E(q_i) − R`, until
    /// the step is below `tol_mm` or after `max_iterations` evaluations (the library's loop,
    /// `controller::fixed_point_mm`). Allocation-free.
    pub(crate) fn solve_mm(
        &mut self,
        p_mm: [f64; 3],
        negative: [bool; 3],
        tol_mm: f64,
        max_iterations: usize,
    ) -> ([f64; 3], SolveInfo) {
        if self.stale {
            self.update_temps();
        }
        let reversal_mm = reversal_mm(negative, self.neg_shift_mm);
        match self.isa {
            // SAFETY: `Isa::Avx2Fma` is chosen only when the CPU reports AVX2 and FMA.
            #[cfg(target_arch = "x86_64")]
            Isa::Avx2Fma => unsafe { self.solve_avx2(p_mm, reversal_mm, tol_mm, max_iterations) },
            _ => self.solve_with::<false>(p_mm, reversal_mm, tol_mm, max_iterations),
        }
    }

    /// Recomputes the readings stage (module doc): runs at the first query after an
    /// observation.
    pub(super) fn update_temps(&mut self) {
        self.stale = false;
        self.inputs.assemble();
        for k in 0..3 {
            let temps = self.inputs.axis_inputs(k);
            let head = &mut self.heads[k];
            head.start_valid = false;
            let c = &mut self.c_scratch[..head.hidden];
            let (mut l, mut l_pos) = ([0.0; N_OUT], [0.0; N_OUT]);
            self.axis_temps[k].set_temps(temps, &mut l, &mut l_pos, c);
            for o in 0..N_OUT {
                head.lin_const[o] = l[o] * head.out_scale[o];
                head.lin_pos[o] = l_pos[o] * head.out_scale[o];
            }
            let m = head.pos_norm[0];
            let units = &mut self.units[head.start..head.start + head.blocks];
            for (j, cj) in c.iter().enumerate() {
                let b = &mut units[j / 4];
                b.c2[j % 4] = 2.0 * cj - b.w2[j % 4] * m;
            }
        }
        let (shared, all) = self.inputs.shared_and_all();
        let s = self.spindle.outputs(all);
        self.spindle_lin_mm = [s[0] * 1e-3, s[1] * 1e-3, s[2] * 1e-3];
        self.spindle_tilt_rad = [s[3] * 1e-6, s[4] * 1e-6];
        let a = self.squareness.predict_urad(shared);
        self.squareness_rad = [a[0] * 1e-6, a[1] * 1e-6, a[2] * 1e-6];
        self.refresh_constant();
    }

    /// The spindle's part of `E` at the tool, `C = δ_b + ε_b × T` (mm), for the held readings and
    /// tool.
    pub(super) fn refresh_constant(&mut self) {
        let t = self.synthesis.tool_offset_mm;
        let sp = self.spindle_lin_mm;
        let tilt = cross([self.spindle_tilt_rad[0], self.spindle_tilt_rad[1], 0.0], t);
        self.constant_mm = [sp[0] + tilt[0], sp[1] + tilt[1], sp[2] + tilt[2]];
    }
}

/// `a × b` (as the synthesis's).
#[inline(always)]
fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}
