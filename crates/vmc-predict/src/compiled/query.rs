//! The query stage of the compiled model: the axis parts at a position, the first-order
//! synthesis and the fixed point of the compensation (module doc of `compiled`).
//!
//! One axis part at position `q` (mm), with `z = (q − m)/σ_q`:
//! `s_j = c_j + w_j·z`, `a_j = tanh(s_j)`, `y_o = (b2_o + Σ_j V_oj·a_j)·σ_o + μ_o`, and the part's
//! output `y_o + (l_o + l'_o·q)` (µm or µrad) with `l`, `l'` the linear part's terms cached for the
//! readings. The sums run in the library's order; the six outputs accumulate side by side over
//! the units (the weights are stored unit-major), which keeps that order per output.

use crate::controller::SolveInfo;

use super::kernel::{exp2_tanh_block, max_step, move_exp2_block, SMALL_STEP_MAX};
use super::CompiledHybrid;

/// Outputs of an axis part: δx, δy, δz (µm), εx, εy, εz (µrad).
pub(super) const N_OUT: usize = 6;
/// Per axis, the head of its region: `[b2 6][σ 6][μ 6][l 6][l' 6][m, σ_q]`.
pub(super) const HEAD: usize = 5 * N_OUT + 2;
/// Hidden layers are padded to a multiple of this many units.
pub(super) const PAD: usize = 4;

/// Where one axis part sits in the hot block: `[head][w Hp][c Hp][V Hp×6][s Hp][s' Hp][e Hp]
/// [a Hp]` from `start`, with `Hp` the padded hidden width.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) struct AxisSlots {
    pub start: usize,
    /// Hidden units of the net (0: linear part only).
    pub hidden: usize,
    /// `hidden` rounded up to a multiple of [`PAD`].
    pub padded: usize,
}

impl AxisSlots {
    /// Values of the region.
    pub fn len(&self) -> usize {
        HEAD + self.padded * (6 + N_OUT)
    }
}

/// The mutable views of one axis region.
struct Region<'a> {
    head: &'a mut [f64],
    w: &'a [f64],
    c: &'a [f64],
    v: &'a [[f64; N_OUT]],
    s: &'a mut [f64],
    s_new: &'a mut [f64],
    e: &'a mut [f64],
    a: &'a mut [f64],
}

fn region(hot: &mut [f64], slots: AxisSlots) -> Region<'_> {
    let hp = slots.padded;
    let r = &mut hot[slots.start..slots.start + slots.len()];
    let (head, r) = r.split_at_mut(HEAD);
    let (w, r) = r.split_at_mut(hp);
    let (c, r) = r.split_at_mut(hp);
    let (v, r) = r.split_at_mut(hp * N_OUT);
    let (s, r) = r.split_at_mut(hp);
    let (s_new, r) = r.split_at_mut(hp);
    let (e, a) = r.split_at_mut(hp);
    Region {
        head,
        w,
        c,
        v: v.as_chunks::<N_OUT>().0,
        s,
        s_new,
        e,
        a,
    }
}

/// The cached linear terms and the first layer's temperature columns of an axis region, for the
/// readings stage to write: `(l, l', c)`.
pub(super) fn temperature_slots(
    hot: &mut [f64],
    slots: AxisSlots,
) -> (&mut [f64], &mut [f64], &mut [f64]) {
    let hp = slots.padded;
    let r = &mut hot[slots.start..slots.start + slots.len()];
    let (head, r) = r.split_at_mut(HEAD);
    let (_, lin) = head.split_at_mut(3 * N_OUT);
    let (lin_const, rest) = lin.split_at_mut(N_OUT);
    let (lin_pos, _) = rest.split_at_mut(N_OUT);
    let (_, r) = r.split_at_mut(hp);
    let (c, _) = r.split_at_mut(hp);
    (lin_const, lin_pos, c)
}

/// The part's outputs from the activations in `r.a` at position `q_mm`.
#[inline(always)]
fn outputs(r: &Region<'_>, q_mm: f64, with_net: bool) -> [f64; N_OUT] {
    let h = &r.head;
    let mut y = [0.0; N_OUT];
    if with_net {
        let mut acc: [f64; N_OUT] = std::array::from_fn(|o| h[o]);
        for (row, aj) in r.v.iter().zip(r.a.iter()) {
            for o in 0..N_OUT {
                acc[o] += row[o] * aj;
            }
        }
        for o in 0..N_OUT {
            y[o] = acc[o] * h[N_OUT + o] + h[2 * N_OUT + o];
        }
    }
    let mut out = [0.0; N_OUT];
    for o in 0..N_OUT {
        out[o] = y[o] + (h[3 * N_OUT + o] + h[4 * N_OUT + o] * q_mm);
    }
    out
}

/// `z` of the position and the units' arguments `s_j = c_j + w_j·z` into `s`.
#[inline(always)]
fn arguments(head: &[f64], w: &[f64], c: &[f64], s: &mut [f64], q_mm: f64) {
    let z = (q_mm - head[5 * N_OUT]) / head[5 * N_OUT + 1];
    for ((s, c), w) in s.iter_mut().zip(c).zip(w) {
        *s = c + w * z;
    }
}

impl CompiledHybrid {
    /// Axis part `k` at `q_mm`, every activation fresh.
    #[inline]
    fn axis_fresh(&mut self, k: usize, q_mm: f64) -> [f64; N_OUT] {
        let slots = self.axes[k];
        let r = region(&mut self.hot, slots);
        let with_net = slots.hidden > 0;
        if with_net {
            arguments(r.head, r.w, r.c, r.s, q_mm);
            exp2_tanh_block(r.s, r.e, r.a);
        }
        outputs(&r, q_mm, with_net)
    }

    /// Axis part `k` at `q_mm`, moved from its last evaluation when every unit's step is small
    /// enough for the polynomial, fresh otherwise.
    #[inline]
    fn axis_moved(&mut self, k: usize, q_mm: f64) -> [f64; N_OUT] {
        let slots = self.axes[k];
        let r = region(&mut self.hot, slots);
        let with_net = slots.hidden > 0;
        if with_net {
            arguments(r.head, r.w, r.c, r.s_new, q_mm);
            if max_step(r.s, r.s_new) <= SMALL_STEP_MAX {
                move_exp2_block(r.s, r.s_new, r.e, r.a);
            } else {
                exp2_tanh_block(r.s_new, r.e, r.a);
            }
            r.s.copy_from_slice(r.s_new);
        }
        outputs(&r, q_mm, with_net)
    }

    /// The first-order synthesis (`synthesis::first_order_error_mm`, same operations in the same
    /// order) of the axis parts' outputs `v` at `q_mm`, with the cached spindle and squareness.
    #[inline]
    fn synthesise_mm(&self, q_mm: [f64; 3], v: &[[f64; N_OUT]; 3]) -> [f64; 3] {
        let g = &self.synthesis;
        let t = g.tool_offset_mm;
        let q = q_mm;
        let mut out = [0.0; 3];
        for k in 0..3 {
            let lin = [v[k][0] * 1e-3, v[k][1] * 1e-3, v[k][2] * 1e-3];
            let ang = [v[k][3] * 1e-6, v[k][4] * 1e-6, v[k][5] * 1e-6];
            let m = &g.arm_mask[k];
            let arm = [t[0] + m[0] * q[0], t[1] + m[1] * q[1], t[2] + m[2] * q[2]];
            let abbe = cross(ang, arm);
            for i in 0..3 {
                out[i] += g.sign[k] * (lin[i] + abbe[i]);
            }
        }
        let sp = self.spindle_lin_mm;
        let tilt = cross([self.spindle_tilt_rad[0], self.spindle_tilt_rad[1], 0.0], t);
        let [yz, xz, xy] = self.squareness_rad;
        [
            out[0] + sp[0] + tilt[0] - q[1] * xy + q[2] * xz,
            out[1] + sp[1] + tilt[1] - q[2] * yz,
            out[2] + sp[2] + tilt[2],
        ]
    }

    /// `E(q)` (mm) with every activation fresh (the readings stage has run).
    #[inline]
    pub(super) fn error_fresh_mm(&mut self, q_mm: [f64; 3]) -> [f64; 3] {
        let v = [
            self.axis_fresh(0, q_mm[0]),
            self.axis_fresh(1, q_mm[1]),
            self.axis_fresh(2, q_mm[2]),
        ];
        self.synthesise_mm(q_mm, &v)
    }

    /// `E(q)` (mm) moved from the previous evaluation (the readings stage has run).
    #[inline]
    fn error_moved_mm(&mut self, q_mm: [f64; 3]) -> [f64; 3] {
        let v = [
            self.axis_moved(0, q_mm[0]),
            self.axis_moved(1, q_mm[1]),
            self.axis_moved(2, q_mm[2]),
        ];
        self.synthesise_mm(q_mm, &v)
    }

    /// The compensation's fixed point for the commanded position `p_mm` (mm), with the
    /// reversal of the axes flagged in `negative`: `q₀ = p`, `q_{i+1} = p − E(q_i) − R`, until
    /// the step is below `tol_mm` or after `max_iterations` evaluations (as
    /// `Compensator::axis_command_mm`, whose arithmetic it repeats). Allocation-free.
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
        let shift = self.neg_shift_mm;
        let reversal_mm: [f64; 3] =
            std::array::from_fn(|k| if negative[k] { shift[k] } else { 0.0 });
        let mut q = p_mm;
        let mut info = SolveInfo::default();
        while info.iterations < max_iterations {
            let mut e = if info.iterations == 0 {
                self.error_fresh_mm(q)
            } else {
                self.error_moved_mm(q)
            };
            for k in 0..3 {
                e[k] += reversal_mm[k];
            }
            let next = [p_mm[0] - e[0], p_mm[1] - e[1], p_mm[2] - e[2]];
            let d = [next[0] - q[0], next[1] - q[1], next[2] - q[2]];
            info.last_step_mm = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
            info.iterations += 1;
            q = next;
            if info.last_step_mm < tol_mm {
                info.converged = true;
                break;
            }
        }
        (q, info)
    }

    /// Recomputes the readings stage (module doc): runs at the first query after an
    /// observation.
    pub(super) fn update_temps(&mut self) {
        self.stale = false;
        self.inputs.assemble();
        for k in 0..3 {
            let temps = self.inputs.axis_inputs(k);
            let (lin_const, lin_pos, c) = temperature_slots(&mut self.hot, self.axes[k]);
            self.axis_temps[k].set_temps(temps, lin_const, lin_pos, c);
        }
        let (shared, all) = self.inputs.shared_and_all();
        let s = self.spindle.outputs(all);
        self.spindle_lin_mm = [s[0] * 1e-3, s[1] * 1e-3, s[2] * 1e-3];
        self.spindle_tilt_rad = [s[3] * 1e-6, s[4] * 1e-6];
        let a = self.squareness.predict_urad(shared);
        self.squareness_rad = [a[0] * 1e-6, a[1] * 1e-6, a[2] * 1e-6];
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
