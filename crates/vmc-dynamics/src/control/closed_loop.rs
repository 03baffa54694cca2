//! The blade with a controller in the loop: poles, attenuation of each mode, actuator effort,
//! the sampled loop's continuous model and the closed-loop stability lobes.
//!
//! Closed loop (controller K: measured displacement y in m → command u in V, strictly proper
//! or with feed-through D_K): state [x; x_K],
//! A_cl = [[A + B_u D_K C_y, B_u C_K], [B_K C_y, A_K]], input the cutting force F (B_w), outputs
//! the tip displacement (C_z) and the command (u = D_K C_y x + C_K x_K).
//!
//! Attenuation of mode k: the peak of |z/F| over the band of that mode (from the geometric
//! mean of its frequency with the one below to the one with the one above) open loop over
//! closed loop, in dB. Effort: the peak of |u/F| in V/N.
//!
//! A sampled controller (rate f_s, the output of sample k applied from sample k + 1 and held)
//! lags by 1.5 samples on its output (one of computation, half of the hold), and its
//! zero-order-hold discretisation sees the measurement held over each sample — half a sample
//! more on the path through its states: [`sampled_model`] puts a second-order Padé
//! approximation of e^(−0.5 s/f_s) before the controller's dynamics (not its feed-through)
//! and one of e^(−1.5 s/f_s) after the whole controller, so a strictly proper controller lags
//! by 2 samples. This is what the closed-loop semi-discretisation uses to compare with the
//! sampled time-domain loop (a model with 1.5 samples only put a lightly damped closed-loop
//! boundary of a perturbed blade 16 % above the sampled loop's; see the decision record on
//! robust chatter control).
//!
//! Closed-loop lobes ([`lobes`]): the semi-discretisation of [`crate::milling`] on the
//! augmented system (structure + actuator + controller states) — the cutting force enters the
//! blade's modes and the regenerative delay acts on the tip displacement only.

use std::ops::Range;

use nalgebra::{Complex, DMatrix};

use super::blade::BladePlant;
use super::pade::pade;
use super::{ControlError, StateSpace};
use crate::converged::Resolution;
use crate::milling::{MillingSdm, SdmOptions};
use crate::params::{positive, DynamicsError, Milling, TipModes, Tool};
use crate::sdm::LobePoint;

/// Frequency points per mode band of the attenuation sweep.
const BAND_POINTS: usize = 3000;

/// The closed loop of a blade and a controller (physical units).
#[derive(Debug, Clone, PartialEq)]
pub struct ClosedLoop {
    /// State matrix [[A + B_u D_K C_y, B_u C_K], [B_K C_y, A_K]].
    pub a: DMatrix<f64>,
    /// Cutting-force input (per N).
    pub b_w: DMatrix<f64>,
    /// Tip displacement output (m).
    pub c_z: DMatrix<f64>,
    /// Command output (V).
    pub c_u: DMatrix<f64>,
}

/// Attenuation of one mode.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ModeAttenuation {
    /// Natural frequency of the mode with the stack held, Hz.
    pub frequency_hz: f64,
    /// Open-loop peak of |z/F| in the mode's band, m/N.
    pub open_peak_m_per_n: f64,
    /// Closed-loop peak of |z/F| in the band, m/N.
    pub closed_peak_m_per_n: f64,
    /// 20 log₁₀(open / closed) in dB.
    pub attenuation_db: f64,
}

/// Joins a blade and a controller (input y in m, output u in V).
pub fn close(plant: &BladePlant, k: &StateSpace) -> Result<ClosedLoop, ControlError> {
    if k.b.ncols() != 1 || k.c.nrows() != 1 {
        return Err(ControlError::Dimension {
            what: "controller inputs/outputs",
            expected: 1,
            got: k.b.ncols().max(k.c.nrows()),
        });
    }
    let (n, nk) = (plant.a.nrows(), k.states());
    let mut a = DMatrix::zeros(n + nk, n + nk);
    a.view_mut((0, 0), (n, n))
        .copy_from(&(&plant.a + &plant.b_u * &k.d * &plant.c_y));
    a.view_mut((0, n), (n, nk)).copy_from(&(&plant.b_u * &k.c));
    a.view_mut((n, 0), (nk, n)).copy_from(&(&k.b * &plant.c_y));
    a.view_mut((n, n), (nk, nk)).copy_from(&k.a);
    let mut b_w = DMatrix::zeros(n + nk, 1);
    b_w.view_mut((0, 0), (n, 1)).copy_from(&plant.b_w);
    let mut c_z = DMatrix::zeros(1, n + nk);
    c_z.view_mut((0, 0), (1, n)).copy_from(&plant.c_z);
    let mut c_u = DMatrix::zeros(1, n + nk);
    c_u.view_mut((0, 0), (1, n)).copy_from(&(&k.d * &plant.c_y));
    c_u.view_mut((0, n), (1, nk)).copy_from(&k.c);
    // The controller's states are free: balance them against the plant's physical states so
    // that eigenvalues, solves and exponentials of A keep their digits.
    let (a, d) = super::balance(&a, n);
    let c_u = DMatrix::from_fn(1, n + nk, |i, j| c_u[(i, j)] * d[j]);
    Ok(ClosedLoop { a, b_w, c_z, c_u })
}

/// The open loop (stack held, u = 0) in the same form.
pub fn open(plant: &BladePlant) -> ClosedLoop {
    ClosedLoop {
        a: plant.a.clone(),
        b_w: plant.b_w.clone(),
        c_z: plant.c_z.clone(),
        c_u: DMatrix::zeros(1, plant.a.nrows()),
    }
}

impl ClosedLoop {
    fn system(&self, c: &DMatrix<f64>) -> StateSpace {
        StateSpace {
            a: self.a.clone(),
            b: self.b_w.clone(),
            c: c.clone(),
            d: DMatrix::zeros(1, 1),
        }
        .balanced()
    }

    /// Closed-loop poles (of the balanced matrix).
    pub fn poles(&self) -> Vec<Complex<f64>> {
        self.system(&self.c_z).poles()
    }

    /// True when every pole has a negative real part.
    pub fn is_stable(&self) -> bool {
        self.poles().iter().all(|l| l.re < 0.0)
    }

    /// Tip receptance z/F at ω, m/N.
    pub fn tip_frf(&self, omega_rad_per_s: f64) -> Complex<f64> {
        self.system(&self.c_z).frf(omega_rad_per_s)[(0, 0)]
    }

    /// Command per force u/F at ω, V/N.
    pub fn effort_frf(&self, omega_rad_per_s: f64) -> Complex<f64> {
        self.system(&self.c_u).frf(omega_rad_per_s)[(0, 0)]
    }

    /// Peak of |u/F| over [lo, hi] Hz: (V/N, Hz).
    pub fn effort_peak(&self, lo_hz: f64, hi_hz: f64) -> (f64, f64) {
        peak(lo_hz, hi_hz, 4 * BAND_POINTS, |w| self.effort_frf(w).norm())
    }
}

fn peak(lo_hz: f64, hi_hz: f64, points: usize, f: impl Fn(f64) -> f64) -> (f64, f64) {
    let ratio = (hi_hz / lo_hz).powf(1.0 / (points - 1) as f64);
    let mut best = (0.0, lo_hz);
    let mut hz = lo_hz;
    for _ in 0..points {
        let v = f(2.0 * std::f64::consts::PI * hz);
        if v > best.0 {
            best = (v, hz);
        }
        hz *= ratio;
    }
    best
}

/// Attenuation of each mode of the held blade (see the module doc).
pub fn attenuation(plant: &BladePlant, closed: &ClosedLoop) -> Vec<ModeAttenuation> {
    let f = plant.frequencies_hz();
    let ol = open(plant);
    (0..f.len())
        .map(|k| {
            let lo = if k == 0 {
                f[0] / 3.0
            } else {
                (f[k - 1] * f[k]).sqrt()
            };
            let hi = if k + 1 == f.len() {
                f[k] * 3.0
            } else {
                (f[k] * f[k + 1]).sqrt()
            };
            let (o, _) = peak(lo, hi, BAND_POINTS, |w| ol.tip_frf(w).norm());
            let (c, _) = peak(lo, hi, BAND_POINTS, |w| closed.tip_frf(w).norm());
            ModeAttenuation {
                frequency_hz: f[k],
                open_peak_m_per_n: o,
                closed_peak_m_per_n: c,
                attenuation_db: 20.0 * (o / c).log10(),
            }
        })
        .collect()
}

/// Continuous model of a controller sampled at `sample_rate_hz` with a one-sample delay and a
/// zero-order hold (see the module doc): the order-2 Padé approximation of e^(−0.5 s/f_s) on
/// the input of K's dynamics, then the one of e^(−1.5 s/f_s) after K.
pub fn sampled_model(k: &StateSpace, sample_rate_hz: f64) -> Result<StateSpace, ControlError> {
    positive("sample_rate_hz", sample_rate_hz)?;
    let k = &held_input(k, &pade(0.5 / sample_rate_hz, 2)?);
    let d = pade(1.5 / sample_rate_hz, 2)?;
    let (n, nd) = (k.states(), d.states());
    let mut a = DMatrix::zeros(n + nd, n + nd);
    a.view_mut((0, 0), (n, n)).copy_from(&k.a);
    a.view_mut((n, 0), (nd, n)).copy_from(&(&d.b * &k.c));
    a.view_mut((n, n), (nd, nd)).copy_from(&d.a);
    let mut b = DMatrix::zeros(n + nd, 1);
    b.view_mut((0, 0), (n, 1)).copy_from(&k.b);
    b.view_mut((n, 0), (nd, 1)).copy_from(&(&d.b * &k.d));
    let mut c = DMatrix::zeros(1, n + nd);
    c.view_mut((0, 0), (1, n)).copy_from(&(&d.d * &k.c));
    c.view_mut((0, n), (1, nd)).copy_from(&d.c);
    StateSpace::new(a, b, c, &d.d * &k.d)
}

/// K with its dynamics fed through the SISO system `h` (the feed-through D_K left direct):
/// states [x_h; x_K].
fn held_input(k: &StateSpace, h: &StateSpace) -> StateSpace {
    let (nh, n) = (h.states(), k.states());
    let mut a = DMatrix::zeros(nh + n, nh + n);
    a.view_mut((0, 0), (nh, nh)).copy_from(&h.a);
    a.view_mut((nh, 0), (n, nh)).copy_from(&(&k.b * &h.c));
    a.view_mut((nh, nh), (n, n)).copy_from(&k.a);
    let mut b = DMatrix::zeros(nh + n, 1);
    b.view_mut((0, 0), (nh, 1)).copy_from(&h.b);
    b.view_mut((nh, 0), (n, 1)).copy_from(&(&k.b * &h.d));
    let mut c = DMatrix::zeros(1, nh + n);
    c.view_mut((0, nh), (1, n)).copy_from(&k.c);
    StateSpace {
        a,
        b,
        c,
        d: k.d.clone(),
    }
}

/// The cut of the lobes: cutter, immersion, milling direction.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LobeCut {
    /// The cutter.
    pub tool: Tool,
    /// Radial immersion a_e/D.
    pub immersion: f64,
    /// Up or down milling.
    pub milling: Milling,
}

/// Semi-discretisation of the blade's milling with the loop `closed` (open or closed).
pub fn sdm(
    plant: &BladePlant,
    closed: &ClosedLoop,
    cut: &LobeCut,
    options: SdmOptions,
) -> Result<MillingSdm, DynamicsError> {
    let modes = TipModes {
        x: Vec::new(),
        y: plant.tip_modes.clone(),
    };
    MillingSdm::new(&cut.tool, &modes, cut.immersion, cut.milling, options)?
        .with_augmented_system(&closed.a, &plant.frequencies_hz())
}

/// Closed-loop stability lobes by semi-discretisation at `resolution` (a count of steps per
/// tooth period converts to [`Resolution::Fixed`]; [`Resolution::default`] chooses and checks
/// the steps per speed, see [`crate::converged`]): the critical depth at each speed to
/// `tol_mm` in (0, `max_depth_mm`]. The blade's higher modes (kHz) can set the closed-loop
/// limit once the first modes are damped; the error of the first-order method grows as
/// (f τ / m)², so they need m ≈ 160 where the open loop's first mode is content with 40. An
/// unstable loop is refused.
pub fn lobes(
    plant: &BladePlant,
    closed: &ClosedLoop,
    cut: &LobeCut,
    speeds_rpm: &[f64],
    (max_depth_mm, tol_mm): (f64, f64),
    resolution: impl Into<Resolution>,
) -> Result<Vec<LobePoint>, ControlError> {
    if !closed.is_stable() {
        return Err(ControlError::UnstableLoop);
    }
    let all = 0..speeds_rpm.len();
    let tol = (max_depth_mm, tol_mm);
    let points = lobes_block(plant, closed, cut, speeds_rpm, all, tol, resolution)?;
    Ok(points.into_iter().flatten().collect())
}

/// The closed-loop lobe points of the block `block` of `speeds_rpm`, one per speed (`None`
/// without a boundary below `max_depth_mm`), bit-identical to the same speeds' points of
/// [`lobes`] over the whole list (see [`MillingSdm::trace_block`]; each run of the trace starts
/// from the whole depth range).
pub fn lobes_block(
    plant: &BladePlant,
    closed: &ClosedLoop,
    cut: &LobeCut,
    speeds_rpm: &[f64],
    block: Range<usize>,
    (max_depth_mm, tol_mm): (f64, f64),
    resolution: impl Into<Resolution>,
) -> Result<Vec<Option<LobePoint>>, ControlError> {
    if !closed.is_stable() {
        return Err(ControlError::UnstableLoop);
    }
    let resolution = resolution.into();
    resolution.validate()?;
    let range = (max_depth_mm, tol_mm);
    Ok(
        sdm(plant, closed, cut, SdmOptions::default())?.trace_block_at(
            speeds_rpm,
            block,
            None,
            range,
            &resolution,
        )?,
    )
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::control::blade::tests::study_blade;
    use crate::control::design::{to_metres, DesignPlant, HinfWeights, LqgWeights};

    pub(crate) fn lqg_weights() -> LqgWeights {
        LqgWeights {
            tip_weight_per_um2: 1.0,
            effort_weight_per_v2: 10.0,
            force_intensity_n2: 1.0,
            noise_intensity_um2: 1e-2,
            lowpass_hz: Some(2000.0),
        }
    }

    pub(crate) fn hinf_weights() -> HinfWeights {
        HinfWeights {
            tip_weight_per_um: 1.0,
            effort_weight_per_v: 1e-2,
            force_scale_n: 1.0,
            noise_scale_um: 1e-3,
            lowpass_hz: None,
        }
    }

    #[test]
    fn lqg_on_the_blade_is_stable_and_damps_the_first_two_modes() {
        let p = study_blade(4).plant().unwrap();
        let k = to_metres(&DesignPlant::structure(&p).lqg(&lqg_weights()).unwrap());
        let cl = close(&p, &k).unwrap();
        assert!(cl.is_stable());
        let att = attenuation(&p, &cl);
        assert!(
            att[0].attenuation_db > 20.0 && att[1].attenuation_db > 6.0,
            "{att:?}"
        );
        // Open-loop peak of mode 1 ≈ 1/(2ζ k_1) with k_1 the held blade's modal stiffness:
        // the same order as the static compliance / (2ζ).
        let static_m_per_n = 1e-3 / p.static_tip_stiffness_n_per_mm();
        let q = att[0].open_peak_m_per_n / static_m_per_n;
        assert!(q > 30.0 && q < 70.0, "{q}");
    }

    /// The acceptance check of the H∞ design: the closed loop's H∞ norm w → z from a frequency
    /// sweep is below the γ the controller was built for.
    #[test]
    fn hinf_closed_loop_norm_on_the_blade_is_below_gamma() {
        let p = study_blade(4).plant().unwrap();
        let dp = DesignPlant::structure(&p);
        let w = hinf_weights();
        let (k, gamma) = dp.hinf(&w).unwrap();
        let g = dp.generalised(&w).unwrap();
        let cl = crate::control::hinf::lower_lft(&g, &k).balanced();
        assert!(cl.poles().iter().all(|l| l.re < 0.0));
        let (norm, _) = crate::control::hinf::hinf_norm_sweep(
            &cl,
            2.0 * std::f64::consts::PI * 10.0,
            2.0 * std::f64::consts::PI * 1e5,
            4000,
        );
        assert!(norm < gamma && norm > 0.5 * gamma, "{norm} vs {gamma}");
        let att = attenuation(&p, &close(&p, &to_metres(&k)).unwrap());
        assert!(att[0].attenuation_db > 20.0, "{att:?}");
    }

    /// At 1696 rpm (a_e/D = 1/16 down milling, 2 teeth, K_t = 1e9, K_n = 3e8 N/m², the LQG
    /// loop sampled at 50 kHz) the fixed 160 steps per tooth period put the closed-loop
    /// boundary 10 % too deep; the converged rule capped at 640 steps (extrapolated from 320
    /// and 640) lies within 0.5 % of 1280 fixed steps and reports its 640 steps.
    #[test]
    fn converged_closed_loop_lobes_report_their_steps_and_beat_the_fixed_160() {
        let p = study_blade(4).plant().unwrap();
        let rate = 50_000.0;
        let design = DesignPlant::structure(&p).sampled(rate).unwrap();
        let k = to_metres(&design.lqg(&lqg_weights()).unwrap());
        let closed = close(&p, &sampled_model(&k, rate).unwrap()).unwrap();
        let cut = LobeCut {
            tool: Tool::new(2, 16.0, 1e9, 3e8),
            immersion: 1.0 / 16.0,
            milling: Milling::Down,
        };
        let at =
            |res: Resolution| lobes(&p, &closed, &cut, &[1696.0], (50.0, 1e-4), res).unwrap()[0];
        let fine = at(Resolution::Fixed(1280));
        let capped = Resolution::Converged(crate::converged::StepRule {
            max_steps: 640,
            ..Default::default()
        });
        let converged = at(capped);
        let coarse = at(160.into());
        let rel = |q: LobePoint| q.critical_depth_mm / fine.critical_depth_mm - 1.0;
        println!(
            "1696 rpm: 1280 steps {:.4} mm, converged {:+.3} %, 160 steps {:+.2} %",
            fine.critical_depth_mm,
            100.0 * rel(converged),
            100.0 * rel(coarse)
        );
        assert!(rel(converged).abs() < 0.005, "{converged:?} vs {fine:?}");
        assert_eq!(converged.steps_per_period, Some(640));
        assert!(rel(coarse) > 0.05, "{coarse:?} vs {fine:?}");
        assert_eq!(coarse.steps_per_period, Some(160));
    }

    #[test]
    fn a_lowpass_filter_cuts_the_high_frequency_effort() {
        let p = study_blade(4).plant().unwrap();
        let dp = DesignPlant::structure(&p);
        let (k, _) = dp.hinf(&hinf_weights()).unwrap();
        let mut w = hinf_weights();
        w.lowpass_hz = Some(3000.0);
        let (kf, _) = dp.hinf(&w).unwrap();
        let e = close(&p, &to_metres(&k))
            .unwrap()
            .effort_peak(5000.0, 20000.0)
            .0;
        let cl = close(&p, &to_metres(&kf)).unwrap();
        assert!(cl.is_stable());
        let ef = cl.effort_peak(5000.0, 20000.0).0;
        assert!(ef < 0.5 * e, "{ef} vs {e}");
    }
}
