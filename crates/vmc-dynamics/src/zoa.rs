//! Zero-order analytic (ZOA) stability lobes of Altintas and Budak.
//!
//! The periodic directional matrix is replaced by its mean A₀ = (N/2π)∫_{φ_st}^{φ_ex} H dφ
//! (see [`crate::forces`]). At the stability limit p = a_p(1 − e^{−iωτ}) G(iω) A₀ p, so with
//! Λ an eigenvalue of G(iω)A₀ (G the tip FRF in m/N):
//!
//! ```text
//! a_lim = 1 / (2 Re Λ)          (only Re Λ > 0 gives a positive depth)
//! e^{iε} = 1 − 2 Re Λ · Λ / |Λ|²,  ε ∈ (0, 2π)    (phase of the regenerative term)
//! τ = (ε + 2kπ)/ω,  n = 60 / (N τ)  for lobes k = 0, 1, 2, …
//! ```
//!
//! For one mode in x, slotting (A₀,xx = −N K_n/4 = −h̄), this reduces to the closed form
//! a_lim,min = 2 k ζ (1 + ζ) / h̄. The mean force cannot represent period doubling: ZOA only
//! finds Hopf lobes and misses flip lobes at low immersion.

use std::f64::consts::PI;

use nalgebra::{Complex, Matrix2};

use crate::forces::{average_cutting_matrix, Engagement};
use crate::modal::ModalModel;
use crate::params::{validate_speed, DynamicsError, Milling, TipModes, Tool};
use crate::sdm::BoundaryKind;
use crate::sdm::LobePoint;

/// Frequency samples of the chatter-frequency scan.
const SCAN_POINTS: usize = 8000;

/// Zero-order analytic model for one tool, tip and engagement.
#[derive(Debug, Clone)]
pub struct Zoa {
    teeth: f64,
    model: ModalModel,
    a0: Matrix2<f64>,
    omegas: Vec<f64>,
}

/// ZOA solution at one chatter frequency for one eigenvalue: depth in mm and phase ε in rad.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ZoaRoot {
    /// Limiting axial depth in mm.
    pub depth_mm: f64,
    /// Regenerative phase ε in (0, 2π).
    pub phase_rad: f64,
}

impl Zoa {
    /// Validates the inputs and averages the directional matrix.
    pub fn new(
        tool: &Tool,
        modes: &TipModes,
        immersion: f64,
        milling: Milling,
    ) -> Result<Self, DynamicsError> {
        tool.validate()?;
        let model = ModalModel::new(modes)?;
        let window = Engagement::new(immersion, milling)?;
        let f = model.frequencies_hz();
        let lo = 0.5 * f.iter().cloned().fold(f64::INFINITY, f64::min);
        let hi = 2.0 * f.iter().cloned().fold(0.0, f64::max);
        let omegas = (0..SCAN_POINTS)
            .map(|i| 2.0 * PI * (lo + (hi - lo) * i as f64 / (SCAN_POINTS - 1) as f64))
            .collect();
        Ok(Self {
            teeth: f64::from(tool.teeth),
            model,
            a0: average_cutting_matrix(tool, &window),
            omegas,
        })
    }

    /// Mean directional matrix A₀ in N/m².
    pub fn mean_directional_matrix(&self) -> Matrix2<f64> {
        self.a0
    }

    /// Eigenvalues Λ of G(iω)A₀ sorted by decreasing real part.
    pub fn eigenvalues(&self, omega_rad_per_s: f64) -> [Complex<f64>; 2] {
        let g = self.model.frf(omega_rad_per_s);
        let a = self.a0.map(|v| Complex::new(v, 0.0));
        let m = g * a;
        let tr = m[(0, 0)] + m[(1, 1)];
        let det = m[(0, 0)] * m[(1, 1)] - m[(0, 1)] * m[(1, 0)];
        let disc = (tr * tr * 0.25 - det).sqrt();
        let (l1, l2) = (tr * 0.5 + disc, tr * 0.5 - disc);
        if l1.re >= l2.re {
            [l1, l2]
        } else {
            [l2, l1]
        }
    }

    /// Root for eigenvalue `branch` (0 = larger Re Λ) at a chatter frequency; `None` if Re Λ ≤ 0.
    pub fn root(&self, omega_rad_per_s: f64, branch: usize) -> Option<ZoaRoot> {
        let l = self.eigenvalues(omega_rad_per_s)[branch];
        if l.re <= 0.0 {
            return None;
        }
        let e = Complex::new(1.0, 0.0) - l * (2.0 * l.re / l.norm_sqr());
        Some(ZoaRoot {
            depth_mm: 1e3 / (2.0 * l.re),
            phase_rad: e.arg().rem_euclid(2.0 * PI),
        })
    }

    fn speed_rpm(&self, omega: f64, phase: f64, lobe: usize) -> f64 {
        60.0 * omega / (self.teeth * (phase + 2.0 * PI * lobe as f64))
    }

    /// Lowest critical depth over all speeds (the asymptote 1/(2 max Re Λ)) and its chatter
    /// frequency in Hz, by a scan and golden-section refinement.
    pub fn minimum_depth(&self) -> (f64, f64) {
        let re = |w: f64| self.eigenvalues(w)[0].re;
        let (mut best_i, mut best) = (0, f64::NEG_INFINITY);
        for (i, &w) in self.omegas.iter().enumerate() {
            let v = re(w);
            if v > best {
                best = v;
                best_i = i;
            }
        }
        let mut a = self.omegas[best_i.saturating_sub(1)];
        let mut b = self.omegas[(best_i + 1).min(self.omegas.len() - 1)];
        let g = (5f64.sqrt() - 1.0) / 2.0;
        for _ in 0..200 {
            let c = b - g * (b - a);
            let d = a + g * (b - a);
            if re(c) > re(d) {
                b = d;
            } else {
                a = c;
            }
        }
        let w = 0.5 * (a + b);
        (1e3 / (2.0 * re(w)), w / (2.0 * PI))
    }

    /// Points (speed, depth, chatter frequency) of lobe k for one eigenvalue branch over the
    /// scanned chatter frequencies, in order of frequency (for plotting lobe diagrams).
    pub fn lobe_curve(&self, lobe: usize, branch: usize) -> Vec<LobePoint> {
        self.omegas
            .iter()
            .filter_map(|&w| {
                self.root(w, branch.min(1)).map(|r| LobePoint {
                    spindle_rpm: self.speed_rpm(w, r.phase_rad, lobe),
                    critical_depth_mm: r.depth_mm,
                    chatter_frequency_hz: w / (2.0 * PI),
                    kind: BoundaryKind::Hopf,
                    steps_per_period: None,
                })
            })
            .collect()
    }

    /// Critical depth at a spindle speed: the smallest depth over lobes and eigenvalues whose
    /// speed n(ω) equals the given one (found by a frequency scan and bisection). `None` when no
    /// lobe reaches that speed in the scanned band (0.5 × lowest to 2 × highest mode).
    pub fn critical_depth(&self, spindle_rpm: f64) -> Result<Option<LobePoint>, DynamicsError> {
        validate_speed(spindle_rpm)?;
        let w_max = *self.omegas.last().unwrap_or(&0.0);
        let max_lobe = (60.0 * w_max / (self.teeth * spindle_rpm * 2.0 * PI)).ceil() as usize + 1;
        let mut best: Option<LobePoint> = None;
        for branch in 0..2 {
            let roots: Vec<Option<ZoaRoot>> =
                self.omegas.iter().map(|&w| self.root(w, branch)).collect();
            for lobe in 0..=max_lobe {
                let f = |w: f64, r: &ZoaRoot| self.speed_rpm(w, r.phase_rad, lobe) - spindle_rpm;
                for i in 1..self.omegas.len() {
                    let (Some(r0), Some(r1)) = (&roots[i - 1], &roots[i]) else {
                        continue;
                    };
                    let (w0, w1) = (self.omegas[i - 1], self.omegas[i]);
                    let (f0, f1) = (f(w0, r0), f(w1, r1));
                    if f0 * f1 > 0.0 {
                        continue;
                    }
                    if let Some((w, r)) = self.refine(w0, w1, f0, branch, lobe, spindle_rpm) {
                        if best.is_none_or(|b| r.depth_mm < b.critical_depth_mm) {
                            best = Some(LobePoint {
                                spindle_rpm,
                                critical_depth_mm: r.depth_mm,
                                chatter_frequency_hz: w / (2.0 * PI),
                                kind: BoundaryKind::Hopf,
                                steps_per_period: None,
                            });
                        }
                    }
                }
            }
        }
        Ok(best)
    }

    /// Bisection of n(ω) − n₀ on [w0, w1]; rejects brackets where n(ω) jumps (phase wrap or
    /// eigenvalue swap) instead of crossing.
    fn refine(
        &self,
        mut w0: f64,
        mut w1: f64,
        mut f0: f64,
        branch: usize,
        lobe: usize,
        n0: f64,
    ) -> Option<(f64, ZoaRoot)> {
        let mut last = None;
        for _ in 0..60 {
            let wm = 0.5 * (w0 + w1);
            let r = self.root(wm, branch)?;
            let fm = self.speed_rpm(wm, r.phase_rad, lobe) - n0;
            if fm * f0 > 0.0 {
                w0 = wm;
                f0 = fm;
            } else {
                w1 = wm;
            }
            last = Some((wm, r, fm));
        }
        let (w, r, fm) = last?;
        (fm.abs() < 1e-6 * n0).then_some((w, r))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::params::Mode;

    /// Insperger–Stépán 1-DOF benchmark: N = 2, K_t = 6e8, K_n = 2e8 N/m², f_n = 922 Hz,
    /// ζ = 0.011, m = 0.03993 kg.
    #[test]
    fn slotting_minimum_matches_closed_form() {
        let tool = Tool::new(2, 20.0, 6e8, 2e8);
        let mode = Mode::from_mass(922.0, 0.011, 0.03993);
        let zoa = Zoa::new(&tool, &TipModes::x_only(vec![mode]), 1.0, Milling::Down).unwrap();
        let h_bar = 2.0 * 2e8 / 4.0;
        let closed_mm = 1e3 * 2.0 * mode.stiffness_n_per_m * 0.011 * 1.011 / h_bar;
        let (a_mm, f_hz) = zoa.minimum_depth();
        assert!(
            (a_mm / closed_mm - 1.0).abs() < 1e-9,
            "{a_mm} vs {closed_mm}"
        );
        // Chatter at r = √(1 + 2ζ), above the natural frequency.
        assert!((f_hz / (922.0 * (1.022f64).sqrt()) - 1.0).abs() < 1e-6);
        // The lobe bottoms approach the minimum: the best of a dense speed scan is within 0.1 %.
        let lowest = (0..200)
            .filter_map(|i| zoa.critical_depth(8000.0 + 40.0 * i as f64).unwrap())
            .map(|p| p.critical_depth_mm)
            .fold(f64::INFINITY, f64::min);
        assert!(
            lowest >= closed_mm * (1.0 - 1e-9) && lowest < closed_mm * 1.001,
            "{lowest}"
        );
        // Every lobe curve has the same minimum depth; lobe k + 1 lies at lower speeds.
        let l0 = zoa.lobe_curve(0, 0);
        let l1 = zoa.lobe_curve(1, 0);
        let min0 = l0
            .iter()
            .map(|p| p.critical_depth_mm)
            .fold(f64::INFINITY, f64::min);
        assert!(min0 >= closed_mm * (1.0 - 1e-9) && min0 < closed_mm * 1.001);
        let at_min = |l: &[LobePoint]| {
            l.iter()
                .min_by(|a, b| a.critical_depth_mm.total_cmp(&b.critical_depth_mm))
                .unwrap()
                .spindle_rpm
        };
        assert!(at_min(&l1) < at_min(&l0));
    }
}
