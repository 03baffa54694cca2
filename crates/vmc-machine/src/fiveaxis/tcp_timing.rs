//! Joint-limited timing of G43.4 moves: the tool tip slows where the machine's axes would
//! otherwise exceed their speed or acceleration limits.
//!
//! # Model
//! Under G43.4 the planner ([`crate::motion`]) lays out each move in the part frame: the tip
//! runs along the programmed line or arc (or stays put while the rotary axes turn) with a
//! trapezoidal profile of the path parameter `σ` (mm of tip path, or degrees of rotary angle
//! for a move of the rotary axes alone) at the programmed feed `v_F` and path acceleration
//! `a_F`. The axes are `q(σ)`: X, Y, Z from the nominal inverse kinematics
//! (`super::plan::joints_for_tip`) and A, B, C linear in `σ`. Near the rotary singularity
//! (B ≈ 0 on a B/C table, A ≈ 0 on an A/C one) a move that swings C quickly drags the linear
//! axes around the C line far faster than the tip moves, so the programmed profile can ask
//! more of an axis than it has.
//!
//! Each move is checked at `N + 1` samples `σ_k = k·Δσ` with `Δσ ≤` [`MAX_STEP`] (0.1 mm of
//! tip path, and at most 0.1° of any rotary axis between samples), between
//! [`MIN_INTERVALS`] and [`MAX_INTERVALS`] intervals. With `q' = dq/dσ` and
//! `q'' = d²q/dσ²` (central differences; one-sided at the ends) an axis's speed and
//! acceleration are `q̇ = q'·σ̇` and `q̈ = q'·σ̈ + q''·σ̇²`. The limits are the machine file's:
//! X, Y, Z at most their rapid rate (`[motion] rapid_mm_per_min`, the axis's top speed) and
//! `max_accel_mm_per_s2`, each rotary axis its `max_speed_deg_per_s` and
//! `max_accel_deg_per_s2`; the tip itself keeps `σ̇ ≤ v_F` and `|σ̈| ≤ a_F`.
//!
//! When the programmed profile meets every limit at every sample the move keeps it unchanged.
//! Otherwise it is retimed as a time-optimal path parametrisation does: in `x = σ̇²` the
//! limits give at each sample a largest admissible `x` (the maximum velocity curve: the speed
//! limits, and the largest `x` at which some `σ̈` meets every acceleration limit, by
//! bisection) and, for a given `x`, a range `[u_lo, u_hi]` of `σ̈`. A forward pass from rest
//! accelerates as hard as allowed (`x_{k+1} = min(MVC_{k+1}, x_k + 2Δσ·u_hi(x_k))`), a
//! backward pass from rest at the end brakes as hard as allowed, and `σ̈` is constant on each
//! interval, so `t_{k+1} − t_k = 2Δσ / (σ̇_k + σ̇_{k+1})`. The axes' speeds at the samples are
//! within their limits by construction; between samples and for the accelerations the
//! sampling leaves an error of the order of `Δσ·|q''|/|q'|` (a few per cent at most on the
//! trunnion examples). A ramp from or to rest shorter than one step costs up to `Δσ/σ̇` of
//! extra time at each end (constant `σ̈` over the first and last interval). The tip stays on
//! the programmed path exactly: only the timing changes.
//!
//! Units: mm, degrees, s.

use crate::motion::{MotionLimits, RotaryLimits, Segment};

/// The linear axes X, Y, Z (mm) for a position (the tool tip in the part frame, mm) at
/// rotary angles A, B, C (degrees): the inverse kinematics under G43.4.
pub type InverseKinematics<'a> = &'a dyn Fn([f64; 3], [f64; 3]) -> [f64; 3];

/// Largest step of the path parameter between samples: mm of tip path (degrees for a move of
/// the rotary axes alone), and degrees of any rotary axis.
pub const MAX_STEP: f64 = 0.1;
/// Fewest intervals a move is sampled with.
pub const MIN_INTERVALS: usize = 16;
/// Most intervals a move is sampled with (2 m of path at 0.1 mm).
pub const MAX_INTERVALS: usize = 20_000;
/// Relative slack on a limit before the programmed profile counts as exceeding it (rounding).
const LIMIT_SLACK: f64 = 1e-9;
/// `|q'|` below which an axis counts as standing still along the path.
const STILL: f64 = 1e-12;

/// The axes' limits, X, Y, Z (mm/s, mm/s²) then A, B, C (deg/s, deg/s²); infinite for a
/// rotary axis the machine lacks.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct JointLimits {
    /// Speed limits.
    pub vel: [f64; 6],
    /// Acceleration limits.
    pub accel: [f64; 6],
}

impl JointLimits {
    /// The limits of a machine file: X, Y, Z's rapid rates and accelerations, the rotary axes'.
    #[must_use]
    pub fn new(motion: &MotionLimits, rotary: &RotaryLimits) -> Self {
        let rapid = motion.rapid_mm_per_min.map(|v| v / 60.0);
        let mut vel = [f64::INFINITY; 6];
        let mut accel = [f64::INFINITY; 6];
        for i in 0..3 {
            vel[i] = rapid[i];
            accel[i] = motion.max_accel_mm_per_s2[i];
            if let Some(l) = rotary.axes[i] {
                vel[3 + i] = l.max_speed_deg_per_s;
                accel[3 + i] = l.max_accel_deg_per_s2;
            }
        }
        Self { vel, accel }
    }
}

/// The axis names in [`JointLimits`] order.
pub const JOINT_NAMES: [char; 6] = ['X', 'Y', 'Z', 'A', 'B', 'C'];

/// Which limit holds the tip back.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LimitKind {
    /// An axis's speed limit.
    Velocity,
    /// An axis's acceleration limit.
    Acceleration,
}

impl LimitKind {
    /// `velocity` or `acceleration`.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Self::Velocity => "velocity",
            Self::Acceleration => "acceleration",
        }
    }
}

/// A move retimed within the axes' limits.
#[derive(Debug, Clone, PartialEq)]
pub struct Retimed {
    /// Step of the path parameter between samples (mm, or degrees).
    step: f64,
    /// Path speed `σ̇` at the samples.
    speed: Vec<f64>,
    /// Time at the samples from the move's start (s).
    time_s: Vec<f64>,
    /// Path length (mm, or degrees).
    length: f64,
    /// The move's duration at the programmed profile (s).
    pub programmed_s: f64,
    /// Lowest admissible path speed along the move over the programmed one (≤ 1; 1 when only
    /// the ramps had to be gentler).
    pub slowest_ratio: f64,
    /// The axis (`X` … `C`) and the kind of limit at the slowest sample.
    pub binding: (char, LimitKind),
}

impl Retimed {
    /// Duration of the retimed move (s).
    #[must_use]
    pub fn duration_s(&self) -> f64 {
        self.time_s.last().copied().unwrap_or(0.0)
    }

    /// Path parameter reached at local time `t_s` (clamped to the move).
    #[must_use]
    pub fn distance_at(&self, t_s: f64) -> f64 {
        if t_s <= 0.0 {
            return 0.0;
        }
        if t_s >= self.duration_s() {
            return self.length;
        }
        let k = self.time_s.partition_point(|&t| t <= t_s).saturating_sub(1);
        let (v0, v1) = (self.speed[k], self.speed[k + 1]);
        let u = (v1 * v1 - v0 * v0) / (2.0 * self.step);
        let tau = t_s - self.time_s[k];
        let ds = (v0 * tau + 0.5 * u * tau * tau).clamp(0.0, self.step);
        (k as f64 * self.step + ds).min(self.length)
    }
}

/// The axes X, Y, Z, A, B, C at path parameter `sigma` of `seg` under G43.4.
fn joints_at(seg: &Segment, ik: InverseKinematics, sigma: f64) -> [f64; 6] {
    let f = sigma / seg.profile.length_mm;
    let p = seg.geometry.point_at(seg.start_mm, sigma);
    let abc =
        [0, 1, 2].map(|i| seg.start_abc_deg[i] + f * (seg.end_abc_deg[i] - seg.start_abc_deg[i]));
    let q = ik(p, abc);
    [q[0], q[1], q[2], abc[0], abc[1], abc[2]]
}

/// The samples' `q'` and `q''` along `seg`, with the step.
fn derivatives(seg: &Segment, ik: InverseKinematics) -> (f64, Vec<[f64; 6]>, Vec<[f64; 6]>) {
    let len = seg.profile.length_mm;
    let turn_deg = (0..3)
        .map(|i| (seg.end_abc_deg[i] - seg.start_abc_deg[i]).abs())
        .fold(0.0, f64::max);
    let n = ((len.max(turn_deg) / MAX_STEP).ceil() as usize).clamp(MIN_INTERVALS, MAX_INTERVALS);
    let h = len / n as f64;
    let q: Vec<[f64; 6]> = (0..=n)
        .map(|k| joints_at(seg, ik, (k as f64 * h).min(len)))
        .collect();
    let mut d1 = vec![[0.0; 6]; n + 1];
    let mut d2 = vec![[0.0; 6]; n + 1];
    for k in 0..=n {
        // Three points around k (shifted inwards at the ends).
        let c = k.clamp(1, n - 1);
        for j in 0..6 {
            let (a, b, e) = (q[c - 1][j], q[c][j], q[c + 1][j]);
            let second = (a - 2.0 * b + e) / (h * h);
            let central = (e - a) / (2.0 * h);
            d2[k][j] = second;
            d1[k][j] = central + (k as f64 - c as f64) * h * second;
        }
    }
    (h, d1, d2)
}

/// One limit's own cap on `x = σ̇²` at a sample: the cap, the axis index, the kind.
type Cap = (f64, usize, LimitKind);

/// A sample's largest admissible `x` and the caps of the single limits.
type SampleCaps = (f64, Vec<Cap>);

/// One sample's limits on the path motion.
#[derive(Clone, Copy)]
struct SampleLimits<'a> {
    d1: &'a [f64; 6],
    d2: &'a [f64; 6],
    lim: &'a JointLimits,
    a_path: f64,
    /// Only this axis's acceleration limit counts (to name the one that binds).
    only: Option<usize>,
}

impl SampleLimits<'_> {
    /// The range of `σ̈` that keeps every acceleration within limits at `x = σ̇²`.
    fn accel_range(&self, x: f64) -> (f64, f64) {
        let (mut lo, mut hi) = (-self.a_path, self.a_path);
        for j in 0..6 {
            let (d1, a) = (self.d1[j], self.lim.accel[j]);
            if d1.abs() < STILL || !a.is_finite() || self.only.is_some_and(|o| o != j) {
                continue;
            }
            let c = self.d2[j] * x;
            let (b1, b2) = ((-a - c) / d1, (a - c) / d1);
            lo = lo.max(b1.min(b2));
            hi = hi.min(b1.max(b2));
        }
        (lo, hi)
    }

    /// Largest `x = σ̇²` allowed by the axes' limits, each limit's own cap and which it is.
    fn caps(&self) -> SampleCaps {
        let mut caps = Vec::new();
        for j in 0..6 {
            let (d1, d2) = (self.d1[j].abs(), self.d2[j].abs());
            if d1 >= STILL && self.lim.vel[j].is_finite() {
                caps.push(((self.lim.vel[j] / d1).powi(2), j, LimitKind::Velocity));
            }
            if d1 < STILL && d2 > 0.0 && self.lim.accel[j].is_finite() {
                caps.push((self.lim.accel[j] / d2, j, LimitKind::Acceleration));
            }
        }
        let x_vel = caps.iter().map(|c| c.0).fold(f64::INFINITY, f64::min);
        let x_max = self.accel_feasible_below(x_vel);
        (x_max, caps)
    }

    /// The largest `x ≤ x_top` at which some `σ̈` meets every acceleration limit (the feasible
    /// `x` form an interval from 0: the range's bounds are linear in `x`).
    fn accel_feasible_below(&self, x_top: f64) -> f64 {
        let ok = |x: f64| {
            let (lo, hi) = self.accel_range(x);
            lo <= hi
        };
        if x_top.is_finite() && ok(x_top) {
            return x_top;
        }
        let mut hi = if x_top.is_finite() { x_top } else { 1.0 };
        if !x_top.is_finite() {
            while ok(hi) && hi < 1e30 {
                hi *= 4.0;
            }
        }
        let mut lo = 0.0;
        for _ in 0..80 {
            let mid = 0.5 * (lo + hi);
            if ok(mid) {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        lo
    }
}

/// The programmed profile's path acceleration at local time `t_s`.
fn programmed_accel(seg: &Segment, t_s: f64) -> f64 {
    let p = &seg.profile;
    if t_s < p.t_accel_s {
        p.accel_mm_per_s2
    } else if t_s <= p.t_accel_s + p.t_cruise_s {
        0.0
    } else {
        -p.accel_mm_per_s2
    }
}

/// The axis and limit the programmed profile exceeds most (demand over limit), `None` when it
/// keeps every axis within its limits at every sample.
fn programmed_violation(
    seg: &Segment,
    h: f64,
    d1: &[[f64; 6]],
    d2: &[[f64; 6]],
    lim: &JointLimits,
) -> Option<(char, LimitKind)> {
    let mut worst: Option<(f64, (char, LimitKind))> = None;
    for k in 0..d1.len() {
        let t_s = seg.profile.time_at_distance(k as f64 * h);
        let v = seg.profile.speed_at(t_s);
        let a = programmed_accel(seg, t_s);
        for j in 0..6 {
            let vel = (d1[k][j] * v).abs() / lim.vel[j];
            let acc = (d1[k][j] * a + d2[k][j] * v * v).abs() / lim.accel[j];
            for (r, kind) in [(vel, LimitKind::Velocity), (acc, LimitKind::Acceleration)] {
                if r > 1.0 + LIMIT_SLACK && worst.is_none_or(|w| r > w.0) {
                    worst = Some((r, (JOINT_NAMES[j], kind)));
                }
            }
        }
    }
    worst.map(|w| w.1)
}

/// Retimes the G43.4 move `seg` (its axes by the inverse kinematics `ik`) within `lim`; `None`
/// when its programmed profile already keeps every axis within its limits (or it does not move).
#[must_use]
pub fn retime(seg: &Segment, ik: InverseKinematics, lim: &JointLimits) -> Option<Retimed> {
    let profile = &seg.profile;
    if profile.length_mm <= 0.0 || seg.duration_s <= 0.0 {
        return None;
    }
    let (h, d1, d2) = derivatives(seg, ik);
    let exceeded = programmed_violation(seg, h, &d1, &d2, lim)?;
    let v_prog = profile.v_limit_mm_per_s;
    let samples: Vec<SampleLimits> = (0..d1.len())
        .map(|k| SampleLimits {
            d1: &d1[k],
            d2: &d2[k],
            lim,
            a_path: profile.accel_mm_per_s2,
            only: None,
        })
        .collect();
    let caps: Vec<SampleCaps> = samples.iter().map(SampleLimits::caps).collect();
    let mvc: Vec<f64> = caps.iter().map(|c| c.0.min(v_prog * v_prog)).collect();
    let x = passes(&samples, &mvc, h);
    let speed: Vec<f64> = x.iter().map(|x| x.max(0.0).sqrt()).collect();
    let mut time_s = Vec::with_capacity(speed.len());
    let mut t = 0.0;
    time_s.push(t);
    for w in speed.windows(2) {
        t += 2.0 * h / (w[0] + w[1]);
        time_s.push(t);
    }
    let (slowest_ratio, binding) = slowest(&samples, &caps, v_prog, exceeded);
    Some(Retimed {
        step: h,
        speed,
        time_s,
        length: profile.length_mm,
        programmed_s: seg.duration_s,
        slowest_ratio,
        binding,
    })
}

/// The forward and backward passes: `x = σ̇²` at the samples, from rest to rest.
fn passes(samples: &[SampleLimits], mvc: &[f64], h: f64) -> Vec<f64> {
    let n = mvc.len() - 1;
    let mut x = vec![0.0; n + 1];
    for k in 0..n {
        let (_, u_hi) = samples[k].accel_range(x[k]);
        x[k + 1] = (x[k] + 2.0 * h * u_hi).clamp(0.0, mvc[k + 1]);
    }
    x[n] = 0.0;
    for k in (0..n).rev() {
        let (u_lo, _) = samples[k + 1].accel_range(x[k + 1]);
        x[k] = x[k].min(x[k + 1] - 2.0 * h * u_lo.min(0.0));
    }
    x[0] = 0.0;
    // Interior samples stay in motion: a zero would stall the move (the caps are positive).
    for (k, xk) in x.iter_mut().enumerate().take(n).skip(1) {
        if *xk <= 0.0 {
            *xk = mvc[k].min(f64::MIN_POSITIVE.sqrt());
        }
    }
    x
}

/// The lowest admissible speed over the programmed one, and which axis limit sets it (where
/// the speed is never capped below the programmed one, `exceeded`: the limit the programmed
/// ramps broke).
fn slowest(
    samples: &[SampleLimits],
    caps: &[SampleCaps],
    v_prog: f64,
    exceeded: (char, LimitKind),
) -> (f64, (char, LimitKind)) {
    let (k, x_min) =
        caps.iter().enumerate().fold(
            (0, f64::INFINITY),
            |acc, (k, c)| if c.0 < acc.1 { (k, c.0) } else { acc },
        );
    let ratio = (x_min.sqrt() / v_prog).min(1.0);
    if ratio >= 1.0 {
        return (1.0, exceeded);
    }
    let named = caps[k]
        .1
        .iter()
        .filter(|c| c.0 <= x_min * (1.0 + 1e-9))
        .min_by(|a, b| a.0.total_cmp(&b.0))
        .map(|c| (JOINT_NAMES[c.1], c.2));
    // Otherwise the accelerations cap the speed: name the axis whose limit alone caps it most.
    let binding = named.unwrap_or_else(|| {
        let s = &samples[k];
        let j = (0..6)
            .map(|j| {
                let alone = SampleLimits {
                    only: Some(j),
                    ..*s
                };
                (j, alone.accel_feasible_below(f64::INFINITY))
            })
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .map_or(0, |c| c.0);
        (JOINT_NAMES[j], LimitKind::Acceleration)
    });
    (ratio, binding)
}

#[cfg(test)]
#[path = "tcp_timing_tests.rs"]
mod tests;
