//! Semi-discretisation of the milling equation: stability at a (speed, depth), grids and a
//! boundary tracer.
//!
//! With the modal state s = [q; q̇] (see [`crate::modal`]) and tip displacements p = C s the
//! milling equation is
//!
//! ```text
//! ṡ = (A₀ + a_p B_in H(t) C − (c_pd a_p / v_c) B_in D(t) C_v) s − a_p B_in H(t) p(t − τ)
//! ```
//!
//! with H, D from [`crate::forces`] (means over each step, integrated exactly including the
//! screen function, so entry and exit inside a step are resolved), τ = 60/(N n) and
//! v_c = πDn/60. It is solved by [`crate::sdm`] with m steps per tooth period (default 40;
//! [`crate::converged`] chooses m per speed for accuracy and extrapolates the spectral radius
//! from two resolutions, [`MillingSdm::at_speed_extrapolated`]).
//! Steps during which no tooth cuts reuse one exponential per speed.
//!
//! Helical teeth: H and D are the disk means of [`crate::forces::helical_cutting_matrix_mean`]
//! with disks one step angle (2π/(N m)) apart in lag at most. The disks depend on the depth,
//! so with a helix the step terms are built for each depth instead of once per speed; straight
//! teeth keep one disk without lag (the straight-tooth model, unchanged).
//!
//! Critical depth at a speed: [`MillingSdm::grid_boundary`] scans a depth grid and returns the
//! midpoint between the last stable and the first unstable depth; [`MillingSdm::trace`]
//! follows the boundary from speed to speed, bracketing around the previous speed's depth and
//! bisecting to a tolerance, which needs far fewer stability evaluations. It starts afresh
//! every [`TRACE_RUN`] speeds of the list, so that any block of the list can be traced on its
//! own with the same result ([`MillingSdm::trace_block`]).

use std::ops::Range;
use std::sync::atomic::{AtomicUsize, Ordering};

use nalgebra::{Complex, DMatrix};

use std::borrow::Cow;

use crate::forces::{
    cutting_speed_m_per_s, helical_cutting_matrix_mean, helical_damping_matrix_mean, Disks,
    Engagement,
};
use crate::modal::ModalModel;
use crate::params::{positive, validate_speed, DynamicsError, Milling, TipModes, Tool};
use crate::sdm::LobePoint;
use crate::sdm::{
    chatter_frequency_hz, classify, critical_multiplier, monodromy_compact, monodromy_from,
    BoundaryKind, Step, StepRef,
};

/// Speeds over which [`MillingSdm::trace_block`] follows the boundary before it starts afresh.
/// Following makes a speed's search cheap (its bracket starts at the depth of the speed before);
/// fresh starts at fixed places of the list let any block of it be traced on its own, with at
/// most `TRACE_RUN − 1` speeds before the block recomputed. (Figures in the decision record on
/// lobe shards.)
pub const TRACE_RUN: usize = 8;

/// Largest step of the upward walk of [`SpeedSdm::critical_depth`], relative to the depth.
const WALK_STEP: f64 = 0.15;

/// Fractions of the previous speed's critical depth probed for unstable islands.
const ISLAND_PROBES: [f64; 2] = [0.55, 0.8];

/// Options of the milling semi-discretisation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SdmOptions {
    /// Steps per tooth period m (default 40; at least 4). The error in the critical depth
    /// falls as (f·τ/m)² with f·τ the vibration cycles per tooth period: on the benchmark at
    /// 6000 rpm (≈ 4.6 cycles) m = 40 is ≈ 4 % deep, m = 160 ≈ 0.3 %.
    pub steps_per_period: usize,
}

impl Default for SdmOptions {
    fn default() -> Self {
        Self {
            steps_per_period: 40,
        }
    }
}

/// Stability of one (speed, depth) point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Stability {
    /// Spectral radius of the monodromy matrix (stable below 1).
    pub spectral_radius: f64,
    /// Critical (largest-modulus) multiplier.
    pub multiplier: Complex<f64>,
    /// Hopf (complex pair) or flip (real, negative).
    pub kind: BoundaryKind,
    /// Chatter frequency in Hz of the critical multiplier (alias nearest a natural frequency).
    pub chatter_frequency_hz: f64,
    /// Richardson's correction included in the spectral radius, (ρ_m − ρ_{m/2})/3, when it is
    /// extrapolated from a companion of half the steps ([`MillingSdm::at_speed_extrapolated`]);
    /// 0 without one.
    pub extrapolation: f64,
}

impl Stability {
    /// True when the spectral radius is below 1.
    pub fn is_stable(&self) -> bool {
        self.spectral_radius < 1.0
    }
}

/// Milling semi-discretisation for one tool, tip and engagement.
#[derive(Debug)]
pub struct MillingSdm {
    tool: Tool,
    model: ModalModel,
    window: Engagement,
    steps: usize,
    a0: DMatrix<f64>,
    b_in: DMatrix<f64>,
    c: DMatrix<f64>,
    c_v: DMatrix<f64>,
    evaluations: AtomicUsize,
    frequencies_hz: Vec<f64>,
}

/// Depth-independent force terms of one step (per metre of depth).
#[derive(Debug, Clone)]
struct StepTerms {
    /// B_in·H_i·C (current-state feedback).
    bhc: DMatrix<f64>,
    /// B_in·H_i (delayed-output input).
    bh: DMatrix<f64>,
    /// B_in·D_i·C_v (process-damping shape).
    bdc: DMatrix<f64>,
}

/// Per-speed precomputation: step-mean force matrices and the free-flight exponential.
#[derive(Debug)]
pub struct SpeedSdm<'a> {
    sdm: &'a MillingSdm,
    spindle_rpm: f64,
    steps: usize,
    period_s: f64,
    dt_s: f64,
    omega_rad_per_s: f64,
    /// Per step; `None` while no tooth cuts. Empty for helical teeth (built per depth).
    terms: Vec<Option<StepTerms>>,
    free: DMatrix<f64>,
    /// The same speed at half the steps, for the extrapolated spectral radius.
    coarse: Option<Box<SpeedSdm<'a>>>,
}

impl MillingSdm {
    /// Validates the inputs and builds the state-space matrices.
    pub fn new(
        tool: &Tool,
        modes: &TipModes,
        immersion: f64,
        milling: Milling,
        options: SdmOptions,
    ) -> Result<Self, DynamicsError> {
        tool.validate()?;
        let model = ModalModel::new(modes)?;
        let window = Engagement::new(immersion, milling)?;
        if options.steps_per_period < 4 {
            return Err(DynamicsError::TooFewSteps {
                name: "steps_per_period",
                min: 4,
                value: options.steps_per_period,
            });
        }
        Ok(Self {
            tool: *tool,
            a0: model.system_matrix(),
            b_in: model.input_matrix(),
            c: model.output_matrix(),
            c_v: model.velocity_output_matrix(),
            window,
            steps: options.steps_per_period,
            evaluations: AtomicUsize::new(0),
            frequencies_hz: model.frequencies_hz(),
            model,
        })
    }

    /// The cutter.
    pub fn tool(&self) -> &Tool {
        &self.tool
    }

    /// Number of stability evaluations (monodromy + eigenvalues) done so far.
    pub fn evaluations(&self) -> usize {
        self.evaluations.load(Ordering::Relaxed)
    }

    /// Precomputes the step terms of one spindle speed (the options' steps per tooth period).
    pub fn at_speed(&self, spindle_rpm: f64) -> Result<SpeedSdm<'_>, DynamicsError> {
        self.at_speed_with_steps(spindle_rpm, self.steps)
    }

    /// Precomputes the step terms of one spindle speed with `steps` steps per tooth period
    /// (at least 4), whatever the options say.
    pub fn at_speed_with_steps(
        &self,
        spindle_rpm: f64,
        steps: usize,
    ) -> Result<SpeedSdm<'_>, DynamicsError> {
        validate_speed(spindle_rpm)?;
        if steps < 4 {
            return Err(DynamicsError::TooFewSteps {
                name: "steps_per_period",
                min: 4,
                value: steps,
            });
        }
        let period_s = self.tool.tooth_period_s(spindle_rpm);
        let dt_s = period_s / steps as f64;
        let omega = 2.0 * std::f64::consts::PI * spindle_rpm / 60.0;
        let terms = if self.tool.lag_rad_per_m() == 0.0 {
            self.step_terms(steps, omega, dt_s, &Disks::new(&self.tool, 0.0, 0.0))
        } else {
            Vec::new()
        };
        Ok(SpeedSdm {
            sdm: self,
            spindle_rpm,
            steps,
            period_s,
            dt_s,
            omega_rad_per_s: omega,
            terms,
            free: (&self.a0 * dt_s).exp(),
            coarse: None,
        })
    }

    /// [`MillingSdm::at_speed_with_steps`] with `2 × coarse_steps` steps and a companion of
    /// `coarse_steps`: its stability extrapolates the spectral radius from the two (see
    /// [`SpeedSdm::stability`]).
    pub fn at_speed_extrapolated(
        &self,
        spindle_rpm: f64,
        coarse_steps: usize,
    ) -> Result<SpeedSdm<'_>, DynamicsError> {
        let coarse = self.at_speed_with_steps(spindle_rpm, coarse_steps)?;
        let mut fine = self.at_speed_with_steps(spindle_rpm, 2 * coarse_steps)?;
        fine.coarse = Some(Box::new(coarse));
        Ok(fine)
    }

    /// Force terms of each of `steps` steps (per metre of depth) for the given disks.
    fn step_terms(
        &self,
        steps: usize,
        omega: f64,
        dt_s: f64,
        disks: &Disks,
    ) -> Vec<Option<StepTerms>> {
        (0..steps)
            .map(|i| {
                let (pa, pb) = (omega * dt_s * i as f64, omega * dt_s * (i + 1) as f64);
                let h = helical_cutting_matrix_mean(&self.tool, &self.window, disks, pa, pb);
                let dm = helical_damping_matrix_mean(&self.tool, &self.window, disks, pa, pb);
                if h.iter().all(|v| *v == 0.0) && dm.iter().all(|v| *v == 0.0) {
                    return None;
                }
                let bh = &self.b_in * self.model.restrict(&h);
                let bhc = &bh * &self.c;
                let bdc = &self.b_in * self.model.restrict(&dm) * &self.c_v;
                Some(StepTerms { bhc, bh, bdc })
            })
            .collect()
    }

    /// Stability at one speed and depth.
    pub fn stability(&self, spindle_rpm: f64, depth_mm: f64) -> Result<Stability, DynamicsError> {
        self.at_speed(spindle_rpm)?.stability(depth_mm)
    }

    /// Spectral radii on a grid: `result[i][j]` at `speeds_rpm[i]`, `depths_mm[j]`.
    pub fn grid(
        &self,
        speeds_rpm: &[f64],
        depths_mm: &[f64],
    ) -> Result<Vec<Vec<f64>>, DynamicsError> {
        speeds_rpm
            .iter()
            .map(|&n| {
                let s = self.at_speed(n)?;
                depths_mm
                    .iter()
                    .map(|&a| Ok(s.stability(a)?.spectral_radius))
                    .collect()
            })
            .collect()
    }

    /// Critical depth per speed from a full depth grid (ascending; every point is evaluated):
    /// midpoint of the first unstable depth and the depth below it; `None` when all are stable.
    pub fn grid_boundary(
        &self,
        speeds_rpm: &[f64],
        depths_mm: &[f64],
    ) -> Result<Vec<Option<LobePoint>>, DynamicsError> {
        speeds_rpm
            .iter()
            .map(|&n| {
                let s = self.at_speed(n)?;
                let mut prev = 0.0;
                let mut found = None;
                for &a in depths_mm {
                    let st = s.stability(a)?;
                    if found.is_none() && !st.is_stable() {
                        found = Some(s.point(0.5 * (prev + a), &st));
                    }
                    prev = a;
                }
                Ok(found)
            })
            .collect()
    }

    /// Boundary tracer: critical depth at each speed (in the given order) to within `tol_mm`,
    /// searching in (0, `max_depth_mm`]; speeds with no boundary below the maximum are omitted.
    /// [`MillingSdm::trace_block`] over the whole list, each run starting from the whole range.
    pub fn trace(
        &self,
        speeds_rpm: &[f64],
        max_depth_mm: f64,
        tol_mm: f64,
    ) -> Result<Vec<LobePoint>, DynamicsError> {
        let all = 0..speeds_rpm.len();
        let points = self.trace_block(speeds_rpm, all, None, max_depth_mm, tol_mm)?;
        Ok(points.into_iter().flatten().collect())
    }

    /// Boundary tracer over the block `block` of `speeds_rpm`: the critical depth at each of its
    /// speeds to within `tol_mm`, searching in (0, `max_depth_mm`], `None` where no boundary
    /// lies below the maximum. The list is traced in runs of [`TRACE_RUN`] speeds (from index
    /// 0, 8, 16, … of the whole list): the first speed of a run searches from `start_mm`
    /// (`None`: the whole range), every other speed from the depth of the one before it (the
    /// whole range after a speed without a boundary). A block is traced from the first speed of
    /// its first run, so its points are bit-identical to the same speeds' points in the trace
    /// of the whole list, wherever the list is split.
    ///
    /// # Errors
    /// A block beyond the list, a bad speed, depth range or tolerance.
    pub fn trace_block(
        &self,
        speeds_rpm: &[f64],
        block: Range<usize>,
        start_mm: Option<f64>,
        max_depth_mm: f64,
        tol_mm: f64,
    ) -> Result<Vec<Option<LobePoint>>, DynamicsError> {
        positive("max_depth_mm", max_depth_mm)?;
        positive("tol_mm", tol_mm)?;
        if let Some(g) = start_mm {
            positive("start_mm", g)?;
        }
        self.trace_runs(speeds_rpm, block, start_mm, |n, guess| {
            self.at_speed(n)?
                .critical_depth(guess, max_depth_mm, tol_mm)
        })
    }

    /// The run structure of [`MillingSdm::trace_block`] with the critical depth of one speed
    /// given by `depth_at(speed, guess)`: checks the block, starts each run of [`TRACE_RUN`]
    /// speeds from `start_mm` and every other speed from the point before it.
    pub(crate) fn trace_runs(
        &self,
        speeds_rpm: &[f64],
        block: Range<usize>,
        start_mm: Option<f64>,
        depth_at: impl Fn(f64, Option<f64>) -> Result<Option<LobePoint>, DynamicsError>,
    ) -> Result<Vec<Option<LobePoint>>, DynamicsError> {
        if block.end > speeds_rpm.len() {
            return Err(DynamicsError::TooManySteps {
                name: "end of the block of speeds",
                max: speeds_rpm.len(),
                value: block.end,
            });
        }
        if block.start > block.end {
            return Err(DynamicsError::TooFewSteps {
                name: "end of the block of speeds",
                min: block.start,
                value: block.end,
            });
        }
        let first = block.start - block.start % TRACE_RUN;
        let mut out = Vec::with_capacity(block.len());
        let mut guess = start_mm;
        for (k, &n) in speeds_rpm.iter().enumerate().take(block.end).skip(first) {
            if k % TRACE_RUN == 0 {
                guess = start_mm;
            }
            let p = depth_at(n, guess)?;
            guess = p.map(|p| p.critical_depth_mm);
            if k >= block.start {
                out.push(p);
            }
        }
        Ok(out)
    }

    /// The highest natural frequency the chatter is referred to (the tip modes', or those given
    /// to [`MillingSdm::with_augmented_system`]), Hz.
    pub fn highest_frequency_hz(&self) -> f64 {
        self.frequencies_hz.iter().copied().fold(0.0, f64::max)
    }

    /// The fraction of a tooth period in which a tooth is in the engagement window, in (0, 1]
    /// (window width × N / 2π; a helix spreads the cut over more of the period).
    pub fn cut_fraction(&self) -> f64 {
        let width = self.window.exit_rad - self.window.entry_rad;
        (width * f64::from(self.tool.teeth) / (2.0 * std::f64::consts::PI)).clamp(1e-9, 1.0)
    }
}

impl SpeedSdm<'_> {
    /// Monodromy matrix at an axial depth in mm.
    pub fn monodromy(&self, depth_mm: f64) -> DMatrix<f64> {
        self.with_steps(depth_mm, |steps| monodromy_from(steps, &self.sdm.c))
    }

    /// [`SpeedSdm::monodromy`] restricted to the states that matter (see
    /// [`crate::sdm::monodromy_compact`]): the same multipliers but for zeros.
    fn monodromy_compact(&self, depth_mm: f64) -> DMatrix<f64> {
        self.with_steps(depth_mm, |steps| monodromy_compact(steps, &self.sdm.c).0)
    }

    /// The steps of one tooth period at an axial depth in mm, handed to `f`.
    fn with_steps<R>(&self, depth_mm: f64, f: impl FnOnce(&[StepRef<'_>]) -> R) -> R {
        let sdm = self.sdm;
        let a_m = depth_mm * 1e-3;
        let pd = sdm.tool.process_damping_n_per_m * a_m
            / cutting_speed_m_per_s(&sdm.tool, self.spindle_rpm);
        let terms = if self.terms.is_empty() {
            // Helical teeth: disks at most one step angle apart in lag, for this depth.
            let step_rad = self.omega_rad_per_s * self.dt_s;
            let disks = Disks::new(&sdm.tool, a_m, step_rad);
            Cow::Owned(sdm.step_terms(self.steps, self.omega_rad_per_s, self.dt_s, &disks))
        } else {
            Cow::Borrowed(self.terms.as_slice())
        };
        let cut_steps: Vec<Option<Step>> = terms
            .iter()
            .map(|t| {
                t.as_ref().map(|t| {
                    let a = &sdm.a0 + &t.bhc * a_m - &t.bdc * pd;
                    let b = &t.bh * (-a_m);
                    Step::new(&a, &b, self.dt_s)
                })
            })
            .collect();
        // Free-flight steps share the per-speed exponential.
        let refs: Vec<StepRef<'_>> = cut_steps
            .iter()
            .map(|s| match s {
                Some(s) => s.as_ref(),
                None => StepRef {
                    p: &self.free,
                    r: None,
                },
            })
            .collect();
        f(&refs)
    }

    /// Stability at an axial depth in mm (counts one evaluation). With a companion of half the
    /// steps the spectral radius is Richardson's extrapolation ρ_m + (ρ_m − ρ_{m/2})/3 (the
    /// first-order error falls as m⁻²) and the multiplier is scaled to it; kind and chatter
    /// frequency are those of the m steps.
    pub fn stability(&self, depth_mm: f64) -> Result<Stability, DynamicsError> {
        crate::params::non_negative("axial_depth_mm", depth_mm)?;
        self.sdm.evaluations.fetch_add(1, Ordering::Relaxed);
        let mu = critical_multiplier(&self.monodromy_compact(depth_mm));
        let rho = mu.norm();
        let extrapolation = match &self.coarse {
            Some(c) => {
                let rho_c = critical_multiplier(&c.monodromy_compact(depth_mm)).norm();
                (rho - rho_c) / 3.0
            }
            None => 0.0,
        };
        let rho_x = (rho + extrapolation).max(0.0);
        Ok(Stability {
            spectral_radius: rho_x,
            multiplier: if rho > 0.0 { mu * (rho_x / rho) } else { mu },
            kind: classify(mu),
            chatter_frequency_hz: chatter_frequency_hz(mu, self.period_s, &self.sdm.frequencies_hz),
            extrapolation,
        })
    }

    /// Steps per tooth period of this discretisation.
    pub fn steps_per_period(&self) -> usize {
        self.steps
    }

    fn point(&self, depth_mm: f64, unstable: &Stability) -> LobePoint {
        LobePoint {
            spindle_rpm: self.spindle_rpm,
            critical_depth_mm: depth_mm,
            chatter_frequency_hz: unstable.chatter_frequency_hz,
            kind: unstable.kind,
            steps_per_period: Some(self.steps),
        }
    }

    /// Critical depth by bracketing and bisection. With a guess (the previous speed's depth)
    /// 0.55 and 0.8 × guess are probed for islands first, then the bracket starts at
    /// guess·(1 ± 5 %) and widens geometrically, upwards by at most 15 % of the depth a step;
    /// without a guess it is (0, max].
    pub fn critical_depth(
        &self,
        guess_mm: Option<f64>,
        max_depth_mm: f64,
        tol_mm: f64,
    ) -> Result<Option<LobePoint>, DynamicsError> {
        let (mut lo, mut hi, mut hi_st);
        let mut lo_rho = None;
        match guess_mm {
            Some(g) if g < max_depth_mm => {
                // Unstable islands (flip lobes) can open below the followed boundary: probe two
                // depths under the guess and restart from the lowest unstable one.
                for frac in ISLAND_PROBES {
                    let st = self.stability(frac * g)?;
                    if !st.is_stable() {
                        return self.bisect(0.0, None, frac * g, st, tol_mm).map(Some);
                    }
                }
                let mut width = 0.05 * g;
                lo = (g - width).max(0.0);
                hi = (g + width).min(max_depth_mm);
                // Move the lower end down until stable.
                while lo > 0.0 {
                    let st = self.stability(lo)?;
                    if st.is_stable() {
                        lo_rho = Some(st.spectral_radius);
                        break;
                    }
                    hi = lo;
                    width *= 2.0;
                    lo = (lo - width).max(0.0);
                }
                hi_st = self.stability(hi)?;
                while hi_st.is_stable() {
                    if hi >= max_depth_mm {
                        return Ok(None);
                    }
                    lo = hi;
                    lo_rho = Some(hi_st.spectral_radius);
                    // Steps of at most WALK_STEP × the depth, so that a narrow unstable band
                    // (the tip of a lobe) above the guess is not stepped over.
                    width = (2.0 * width).min(WALK_STEP * hi);
                    hi = (hi + width).min(max_depth_mm);
                    hi_st = self.stability(hi)?;
                }
            }
            _ => {
                lo = 0.0;
                hi = max_depth_mm;
                hi_st = self.stability(hi)?;
                if hi_st.is_stable() {
                    return Ok(None);
                }
            }
        }
        self.bisect(lo, lo_rho, hi, hi_st, tol_mm).map(Some)
    }

    /// The lowest critical depth at this speed: the first unstable depth of an even scan of
    /// `scan` depths over (0, `max_depth_mm`], refined by bisection against the depth before it
    /// to `tol_mm`; `None` when every scanned depth is stable. Unlike the tracer it cannot step
    /// over an unstable island wider than the scan's spacing under a higher boundary.
    pub fn lowest_critical_depth(
        &self,
        max_depth_mm: f64,
        scan: usize,
        tol_mm: f64,
    ) -> Result<Option<LobePoint>, DynamicsError> {
        positive("max_depth_mm", max_depth_mm)?;
        positive("tol_mm", tol_mm)?;
        let (mut lo, mut lo_rho) = (0.0, None);
        for k in 1..=scan.max(1) {
            let a = max_depth_mm * k as f64 / scan.max(1) as f64;
            let st = self.stability(a)?;
            if !st.is_stable() {
                return self.bisect(lo, lo_rho, a, st, tol_mm).map(Some);
            }
            (lo, lo_rho) = (a, Some(st.spectral_radius));
        }
        Ok(None)
    }

    /// Narrows a stable `lo` (its spectral radius when known) and an unstable `hi` (with its
    /// stability) to a bracket at most `tol_mm` wide and returns its midpoint, by the ITP method
    /// (interpolate, truncate, project: Oliveira & Takahashi, 2021) on ρ(a) − 1: regula falsi
    /// steps pulled towards the midpoint and kept within a bisection's worst case plus one
    /// step. The spectral radius is smooth in the depth near most boundaries, so this takes
    /// about half the evaluations of bisection; where it is not (two lobes crossing) it falls
    /// back to bisection's count. While ρ(lo) is unknown the step is the midpoint.
    fn bisect(
        &self,
        mut lo: f64,
        mut lo_rho: Option<f64>,
        mut hi: f64,
        mut hi_st: Stability,
        tol_mm: f64,
    ) -> Result<LobePoint, DynamicsError> {
        let eps = 0.5 * tol_mm;
        let width0 = hi - lo;
        let n_max = if width0 > tol_mm {
            (width0 / tol_mm).log2().ceil() as i32 + 1
        } else {
            0
        };
        let k1 = 0.2 / width0.max(f64::MIN_POSITIVE);
        let mut j = 0;
        while hi - lo > tol_mm {
            let mid = 0.5 * (lo + hi);
            let x = match lo_rho {
                Some(rho_lo) => {
                    let (f_lo, f_hi) = (rho_lo - 1.0, hi_st.spectral_radius - 1.0);
                    let x_f = if f_hi > f_lo {
                        (f_hi * lo - f_lo * hi) / (f_hi - f_lo)
                    } else {
                        mid
                    };
                    let sigma = (mid - x_f).signum();
                    let delta = k1 * (hi - lo).powi(2);
                    let x_t = if delta <= (mid - x_f).abs() {
                        x_f + sigma * delta
                    } else {
                        mid
                    };
                    let r = (eps * 2f64.powi(n_max - j) - 0.5 * (hi - lo)).max(0.0);
                    if (x_t - mid).abs() <= r {
                        x_t
                    } else {
                        mid - sigma * r
                    }
                }
                None => mid,
            };
            // Strictly inside the bracket, so that every step narrows it.
            let x = x.clamp(lo + 0.01 * tol_mm, hi - 0.01 * tol_mm);
            let st = self.stability(x)?;
            if st.is_stable() {
                lo = x;
                lo_rho = Some(st.spectral_radius);
            } else {
                hi = x;
                hi_st = st;
            }
            j += 1;
        }
        Ok(self.point(0.5 * (lo + hi), &hi_st))
    }
}

/// Structures with more states than the tip modes (a blade propped by an actuator, a
/// controller in the loop).
impl MillingSdm {
    /// Replaces the free structure ṡ = A₀ s by a linear system ż = A z whose first 2n states
    /// are the modal state [q; q̇] of the tip modes given to [`MillingSdm::new`] (the cutting
    /// force still enters q̈ through the modal masses and the tip displacement is still Σq);
    /// the other states (actuator, controller, …) see the cut only through A.
    /// `frequencies_hz` are the natural frequencies the chatter frequency is referred to.
    pub fn with_augmented_system(
        mut self,
        a: &DMatrix<f64>,
        frequencies_hz: &[f64],
    ) -> Result<Self, DynamicsError> {
        let n = self.a0.nrows();
        if a.nrows() != a.ncols() || a.nrows() < n {
            return Err(DynamicsError::TooFewSteps {
                name: "augmented system size",
                min: n,
                value: a.nrows().min(a.ncols()),
            });
        }
        if let Some(bad) = a.iter().find(|v| !v.is_finite()) {
            crate::params::finite("augmented system", *bad)?;
        }
        let big = a.nrows();
        let grow_rows = |m: &DMatrix<f64>| {
            let mut out = DMatrix::zeros(big, m.ncols());
            out.view_mut((0, 0), (n, m.ncols())).copy_from(m);
            out
        };
        let grow_cols = |m: &DMatrix<f64>| {
            let mut out = DMatrix::zeros(m.nrows(), big);
            out.view_mut((0, 0), (m.nrows(), n)).copy_from(m);
            out
        };
        self.b_in = grow_rows(&self.b_in);
        self.c = grow_cols(&self.c);
        self.c_v = grow_cols(&self.c_v);
        self.a0 = a.clone();
        if !frequencies_hz.is_empty() {
            self.frequencies_hz = frequencies_hz.to_vec();
        }
        Ok(self)
    }
}

/// Feed directions other than the tip's x axis.
impl MillingSdm {
    /// Like [`MillingSdm::new`] for a feed direction at `feed_angle_rad` (counter-clockwise)
    /// from the x axis of the tip modes, as when the modes are given in a machine's X/Y and the
    /// tool feeds along any direction of the plane: the engagement window is turned by
    /// [`Engagement::rotated`] into the frame of the modes.
    pub fn with_feed_angle(
        tool: &Tool,
        modes: &TipModes,
        immersion: f64,
        milling: Milling,
        feed_angle_rad: f64,
        options: SdmOptions,
    ) -> Result<Self, DynamicsError> {
        crate::params::finite("feed_angle_rad", feed_angle_rad)?;
        let mut sdm = Self::new(tool, modes, immersion, milling, options)?;
        sdm.window = sdm.window.rotated(feed_angle_rad);
        Ok(sdm)
    }
}
