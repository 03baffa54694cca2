//! Controller designs for the blade: LQG and H∞, strategy 1 (structure alone) or strategy 2
//! (structure coupled to the cutting process with a Padé delay).
//!
//! Scaling: the physical states (m, m/s, V) span ten orders of magnitude, so the designs work
//! on x̃ = S x with S = diag(10⁶ ω_k for q_k, 10⁶ for q̇_k, 1 for e): modal displacements and
//! velocities in µm/s, outputs in µm. The controller's internal coordinates are free, so only
//! its input is converted back (B_K, D_K × 10⁶ per m of measured displacement).
//!
//! Strategy 2 adds the mean cutting force of the design cut to the plant,
//! F = a_p h̄ (z − D(s) z) + w, with h̄ the yy entry of the mean directional matrix of
//! [`crate::forces::average_cutting_matrix`] (the blade bends along y, normal to the feed) and
//! D(s) the Padé approximation of e^(−sτ), τ the tooth period at the design speed.

use nalgebra::DMatrix;
use serde::{Deserialize, Serialize};

use super::blade::BladePlant;
use super::hinf::{hinf, GeneralisedPlant};
use super::lqg::lqg;
use super::pade::pade;
use super::{ControlError, StateSpace};
use crate::forces::{average_cutting_matrix, Engagement};
use crate::params::{positive, DynamicsError, Milling, Tool};

/// Metres to micrometres.
const UM_PER_M: f64 = 1e6;

/// LQG weights and noise levels (in the scaled units: µm, V, N).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LqgWeights {
    /// Weight on the squared tip displacement, per µm².
    pub tip_weight_per_um2: f64,
    /// Weight on the squared command, per V².
    pub effort_weight_per_v2: f64,
    /// Intensity of the white cutting-force disturbance, N²/Hz.
    pub force_intensity_n2: f64,
    /// Intensity of the white measurement noise, µm²/Hz.
    pub noise_intensity_um2: f64,
    /// Corner of an optional first-order low-pass filter on the controller output, Hz (the
    /// design sees the plant through it, as for H∞).
    #[serde(default)]
    pub lowpass_hz: Option<f64>,
}

/// H∞ weights (the performance output z = [w_z · tip (µm); w_u · u (V)], the disturbance
/// w = [F/σ_F; n/σ_n]).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct HinfWeights {
    /// Weight w_z on the tip displacement, per µm.
    pub tip_weight_per_um: f64,
    /// Weight w_u on the command, per V.
    pub effort_weight_per_v: f64,
    /// Scale σ_F of the cutting-force disturbance, N.
    pub force_scale_n: f64,
    /// Scale σ_n of the measurement noise, µm.
    pub noise_scale_um: f64,
    /// Corner of an optional first-order low-pass filter on the controller output, Hz.
    pub lowpass_hz: Option<f64>,
}

/// The cut that strategy 2 designs on.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CuttingCoupling {
    /// The cutter.
    pub tool: Tool,
    /// Radial immersion a_e/D.
    pub immersion: f64,
    /// Up or down milling.
    pub milling: Milling,
    /// Design axial depth in mm.
    pub depth_mm: f64,
    /// Design spindle speed in rpm.
    pub spindle_rpm: f64,
    /// Order of the Padé approximation of the delay.
    pub pade_order: usize,
}

/// The scaled design plant ẋ = A x + B_w F + B_u u, y = C_y x (µm), z = C_z x (µm).
#[derive(Debug, Clone, PartialEq)]
pub struct DesignPlant {
    /// A.
    pub a: DMatrix<f64>,
    /// B_w (per N).
    pub b_w: DMatrix<f64>,
    /// B_u (per V).
    pub b_u: DMatrix<f64>,
    /// C_y (µm).
    pub c_y: DMatrix<f64>,
    /// C_z (µm).
    pub c_z: DMatrix<f64>,
}

impl DesignPlant {
    /// Strategy 1: the scaled blade.
    pub fn structure(plant: &BladePlant) -> Self {
        let n = plant.modes();
        let size = plant.a.nrows();
        let s: Vec<f64> = (0..size)
            .map(|i| match i {
                i if i < n => UM_PER_M * plant.tip_modes[i].omega_rad_per_s(),
                i if i < 2 * n => UM_PER_M,
                _ => 1.0,
            })
            .collect();
        let a = DMatrix::from_fn(size, size, |i, j| plant.a[(i, j)] * s[i] / s[j]);
        let rows = |m: &DMatrix<f64>| DMatrix::from_fn(size, 1, |i, j| m[(i, j)] * s[i]);
        let cols = |m: &DMatrix<f64>| DMatrix::from_fn(1, size, |i, j| m[(i, j)] * UM_PER_M / s[j]);
        Self {
            a,
            b_w: rows(&plant.b_w),
            b_u: rows(&plant.b_u),
            c_y: cols(&plant.c_y),
            c_z: cols(&plant.c_z),
        }
    }

    /// Strategy 2: the structure with the mean cutting force of a cut and a Padé delay.
    pub fn coupled(plant: &BladePlant, cut: &CuttingCoupling) -> Result<Self, ControlError> {
        positive("design depth_mm", cut.depth_mm)?;
        cut.tool.validate()?;
        let s = Self::structure(plant);
        let window = Engagement::new(cut.immersion, cut.milling)?;
        let h = average_cutting_matrix(&cut.tool, &window)[(1, 1)];
        let k = cut.depth_mm * 1e-3 * h / UM_PER_M; // N per µm of (z − D z)
        let d = pade(cut.tool.tooth_period_s(cut.spindle_rpm), cut.pade_order)?;
        let (n, nd) = (s.a.nrows(), d.states());
        let mut a = DMatrix::zeros(n + nd, n + nd);
        let dz = d.d[(0, 0)];
        a.view_mut((0, 0), (n, n))
            .copy_from(&(&s.a + &s.b_w * &s.c_z * (k * (1.0 - dz))));
        a.view_mut((0, n), (n, nd))
            .copy_from(&(&s.b_w * &d.c * (-k)));
        a.view_mut((n, 0), (nd, n)).copy_from(&(&d.b * &s.c_z));
        a.view_mut((n, n), (nd, nd)).copy_from(&d.a);
        let pad = |m: &DMatrix<f64>| {
            let mut out = DMatrix::zeros(n + nd, m.ncols());
            out.view_mut((0, 0), (n, m.ncols())).copy_from(m);
            out
        };
        let padc = |m: &DMatrix<f64>| {
            let mut out = DMatrix::zeros(1, n + nd);
            out.view_mut((0, 0), (1, n)).copy_from(m);
            out
        };
        Ok(Self {
            a,
            b_w: pad(&s.b_w),
            b_u: pad(&s.b_u),
            c_y: padc(&s.c_y),
            c_z: padc(&s.c_z),
        })
    }

    /// LQG controller (input y in µm, output u in V).
    pub fn lqg(&self, w: &LqgWeights) -> Result<StateSpace, ControlError> {
        positive("tip_weight_per_um2", w.tip_weight_per_um2)?;
        positive("effort_weight_per_v2", w.effort_weight_per_v2)?;
        positive("force_intensity_n2", w.force_intensity_n2)?;
        positive("noise_intensity_um2", w.noise_intensity_um2)?;
        if let Some(hz) = w.lowpass_hz {
            let inner = LqgWeights {
                lowpass_hz: None,
                ..*w
            };
            let k = self.series_input(&lowpass_filter(hz)?).lqg(&inner)?;
            return lowpass(&k, hz);
        }
        let m = |v: f64| DMatrix::from_element(1, 1, v);
        let q = self.c_z.transpose() * &self.c_z * w.tip_weight_per_um2;
        Ok(lqg(
            &self.a,
            &self.b_u,
            &self.b_w,
            &self.c_y,
            (&q, &m(w.effort_weight_per_v2)),
            (&m(w.force_intensity_n2), &m(w.noise_intensity_um2)),
        )?
        .controller)
    }

    /// The generalised plant of the H∞ design.
    pub fn generalised(&self, w: &HinfWeights) -> Result<GeneralisedPlant, ControlError> {
        positive("tip_weight_per_um", w.tip_weight_per_um)?;
        positive("effort_weight_per_v", w.effort_weight_per_v)?;
        positive("force_scale_n", w.force_scale_n)?;
        positive("noise_scale_um", w.noise_scale_um)?;
        let n = self.a.nrows();
        let mut b1 = DMatrix::zeros(n, 2);
        b1.view_mut((0, 0), (n, 1))
            .copy_from(&(&self.b_w * w.force_scale_n));
        let mut c1 = DMatrix::zeros(2, n);
        c1.view_mut((0, 0), (1, n))
            .copy_from(&(&self.c_z * w.tip_weight_per_um));
        Ok(GeneralisedPlant {
            a: self.a.clone(),
            b1,
            b2: self.b_u.clone(),
            c1,
            d12: DMatrix::from_row_slice(2, 1, &[0.0, w.effort_weight_per_v]),
            c2: self.c_y.clone(),
            d21: DMatrix::from_row_slice(1, 2, &[0.0, w.noise_scale_um]),
        })
    }

    /// The plant seen through a SISO system `f` on its command (f's states appended):
    /// the command v drives f, whose output drives the plant.
    pub fn series_input(&self, f: &StateSpace) -> Self {
        let (n, nf) = (self.a.nrows(), f.states());
        let mut a = DMatrix::zeros(n + nf, n + nf);
        a.view_mut((0, 0), (n, n)).copy_from(&self.a);
        a.view_mut((0, n), (n, nf)).copy_from(&(&self.b_u * &f.c));
        a.view_mut((n, n), (nf, nf)).copy_from(&f.a);
        let mut b_u = DMatrix::zeros(n + nf, 1);
        b_u.view_mut((0, 0), (n, 1)).copy_from(&(&self.b_u * &f.d));
        b_u.view_mut((n, 0), (nf, 1)).copy_from(&f.b);
        let grow = |m: &DMatrix<f64>| {
            let mut out = DMatrix::zeros(n + nf, 1);
            out.view_mut((0, 0), (n, 1)).copy_from(m);
            out
        };
        let growc = |m: &DMatrix<f64>| {
            let mut out = DMatrix::zeros(1, n + nf);
            out.view_mut((0, 0), (1, n)).copy_from(m);
            out
        };
        Self {
            a,
            b_w: grow(&self.b_w),
            b_u,
            c_y: growc(&self.c_y),
            c_z: growc(&self.c_z),
        }
    }

    /// The plant behind a controller sampled at `sample_rate_hz`: its command delayed by the
    /// Padé model of 2 samples, the lag of a strictly proper sampled controller (see
    /// [`super::closed_loop::sampled_model`]).
    pub fn sampled(&self, sample_rate_hz: f64) -> Result<Self, ControlError> {
        positive("sample_rate_hz", sample_rate_hz)?;
        Ok(self.series_input(&pade(2.0 / sample_rate_hz, 2)?))
    }

    /// H∞ controller (input y in µm, output u in V) and its γ. With a low-pass filter the
    /// design is done on the plant seen through the filter (so the filtered loop keeps the
    /// guarantee) and the filter is then appended to the controller.
    pub fn hinf(&self, w: &HinfWeights) -> Result<(StateSpace, f64), ControlError> {
        match w.lowpass_hz {
            Some(hz) => {
                let p = self.series_input(&lowpass_filter(hz)?).generalised(w)?;
                let h = hinf(&p, 1e-6, 1e6, 1e-3, 0.05)?;
                Ok((lowpass(&h.controller, hz)?, h.gamma))
            }
            None => {
                let h = hinf(&self.generalised(w)?, 1e-6, 1e6, 1e-3, 0.05)?;
                Ok((h.controller, h.gamma))
            }
        }
    }
}

impl DesignPlant {
    /// Robust H∞ controller (input y in µm, output u in V) and its γ: the design of
    /// [`DesignPlant::hinf`] (its low-pass corner ignored) on the plant seen through the
    /// second-order roll-off of `r`, with the input-multiplicative uncertainty channel
    /// w_Δ → W_Δ(s) → command and its output z_Δ = command (see [`super::robust`]); the
    /// roll-off is then appended to the controller.
    ///
    /// # Errors
    /// Weights out of range, no stabilising design.
    pub fn robust_hinf(
        &self,
        w: &HinfWeights,
        r: &RobustWeights,
    ) -> Result<(StateSpace, f64), ControlError> {
        r.validate()?;
        let f = lowpass_filter(r.rolloff_hz)?;
        let shaped = self.series_input(&f).series_input(&f);
        let g = shaped.generalised(&HinfWeights {
            lowpass_hz: None,
            ..*w
        })?;
        let wd = r.uncertainty_weight();
        let n = g.a.nrows();
        let mut a = DMatrix::zeros(n + 1, n + 1);
        a.view_mut((0, 0), (n, n)).copy_from(&g.a);
        a.view_mut((0, n), (n, 1))
            .copy_from(&(&g.b2 * wd.c[(0, 0)]));
        a[(n, n)] = wd.a[(0, 0)];
        let m1 = g.b1.ncols();
        let mut b1 = DMatrix::zeros(n + 1, m1 + 1);
        b1.view_mut((0, 0), (n, m1)).copy_from(&g.b1);
        b1.view_mut((0, m1), (n, 1))
            .copy_from(&(&g.b2 * wd.d[(0, 0)]));
        b1[(n, m1)] = wd.b[(0, 0)];
        let mut b2 = DMatrix::zeros(n + 1, 1);
        b2.view_mut((0, 0), (n, 1)).copy_from(&g.b2);
        let p1 = g.c1.nrows();
        let mut c1 = DMatrix::zeros(p1 + 1, n + 1);
        c1.view_mut((0, 0), (p1, n)).copy_from(&g.c1);
        let mut d12 = DMatrix::zeros(p1 + 1, 1);
        d12.view_mut((0, 0), (p1, 1)).copy_from(&g.d12);
        d12[(p1, 0)] = 1.0;
        let mut c2 = DMatrix::zeros(1, n + 1);
        c2.view_mut((0, 0), (1, n)).copy_from(&g.c2);
        let mut d21 = DMatrix::zeros(1, m1 + 1);
        d21.view_mut((0, 0), (1, m1)).copy_from(&g.d21);
        let p = GeneralisedPlant {
            a,
            b1,
            b2,
            c1,
            d12,
            c2,
            d21,
        };
        let h = hinf(&p, 1e-6, 1e6, 1e-3, 0.05)?;
        Ok((
            lowpass(&lowpass(&h.controller, r.rolloff_hz)?, r.rolloff_hz)?,
            h.gamma,
        ))
    }
}

/// The filter ω_f/(s + ω_f) alone.
pub fn lowpass_filter(corner_hz: f64) -> Result<StateSpace, ControlError> {
    positive("lowpass_hz", corner_hz)?;
    let wf = 2.0 * std::f64::consts::PI * corner_hz;
    StateSpace::new(
        DMatrix::from_element(1, 1, -wf),
        DMatrix::from_element(1, 1, wf),
        DMatrix::from_element(1, 1, 1.0),
        DMatrix::zeros(1, 1),
    )
}

/// A controller followed by a first-order low-pass filter ω_f/(s + ω_f) on its output.
pub fn lowpass(k: &StateSpace, corner_hz: f64) -> Result<StateSpace, ControlError> {
    positive("lowpass_hz", corner_hz)?;
    let wf = 2.0 * std::f64::consts::PI * corner_hz;
    let (n, p) = (k.states(), k.b.ncols());
    let mut a = DMatrix::zeros(n + 1, n + 1);
    a.view_mut((0, 0), (n, n)).copy_from(&k.a);
    a.view_mut((n, 0), (1, n)).copy_from(&(&k.c * wf));
    a[(n, n)] = -wf;
    let mut b = DMatrix::zeros(n + 1, p);
    b.view_mut((0, 0), (n, p)).copy_from(&k.b);
    b.view_mut((n, 0), (1, p)).copy_from(&(&k.d * wf));
    let mut c = DMatrix::zeros(1, n + 1);
    c[(0, n)] = 1.0;
    StateSpace::new(a, b, c, DMatrix::zeros(1, p))
}

/// Converts a controller designed for y in µm to y in m.
pub fn to_metres(k: &StateSpace) -> StateSpace {
    StateSpace {
        a: k.a.clone(),
        b: &k.b * UM_PER_M,
        c: k.c.clone(),
        d: &k.d * UM_PER_M,
    }
}

/// The weights of the robust H∞ design on top of [`HinfWeights`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RobustWeights {
    /// Relative input uncertainty at low frequency r₀.
    pub uncertainty_low: f64,
    /// Relative input uncertainty at high frequency r_∞.
    pub uncertainty_high: f64,
    /// Frequency ω₀/2π where the uncertainty starts to rise, Hz.
    pub uncertainty_corner_hz: f64,
    /// Corner of the second-order roll-off of the command (two first-order filters), Hz.
    pub rolloff_hz: f64,
}

impl RobustWeights {
    /// Checks every field.
    ///
    /// # Errors
    /// A weight that is not positive and finite, or r_∞ below r₀.
    pub fn validate(&self) -> Result<(), DynamicsError> {
        positive("uncertainty_low", self.uncertainty_low)?;
        positive("uncertainty_high", self.uncertainty_high)?;
        positive("uncertainty_corner_hz", self.uncertainty_corner_hz)?;
        positive("rolloff_hz", self.rolloff_hz)?;
        positive(
            "uncertainty_high - uncertainty_low",
            self.uncertainty_high - self.uncertainty_low,
        )
    }

    /// The uncertainty weight W_Δ(s) as a state-space system (one state).
    pub fn uncertainty_weight(&self) -> StateSpace {
        use nalgebra::DMatrix;
        let (r0, ri) = (self.uncertainty_low, self.uncertainty_high);
        let w0 = 2.0 * std::f64::consts::PI * self.uncertainty_corner_hz;
        // W(s) = r0 (s/w0 + 1)/(s/(w0 ri/r0) + 1) = ri + (r0 - ri) p/(s + p), p = w0 ri/r0.
        let p = w0 * ri / r0;
        StateSpace {
            a: DMatrix::from_element(1, 1, -p),
            b: DMatrix::from_element(1, 1, p),
            c: DMatrix::from_element(1, 1, r0 - ri),
            d: DMatrix::from_element(1, 1, ri),
        }
    }
}
