//! Modal fit of a measured tool-tip receptance: natural frequency, damping ratio and modal
//! stiffness (and mass) of each mode, per direction, as the [`TipModes`] that the stability
//! methods take.
//!
//! **File format** (CSV, parsed from text by [`Frf::parse`]): blank lines and lines starting
//! with `#` are skipped; the first other line is the header, naming the columns in any order:
//!
//! ```text
//! frequency_hz,x_re_m_per_n,x_im_m_per_n,y_re_m_per_n,y_im_m_per_n
//! 100,1.02e-7,-3.1e-9,9.8e-8,-2.7e-9
//! 102,1.02e-7,-3.2e-9,9.8e-8,-2.8e-9
//! ```
//!
//! `frequency_hz` (≥ 0, strictly increasing) and, per direction x (feed) and y, the real and
//! imaginary parts of the receptance (displacement per force at the tool tip, m/N). A
//! direction may be left out entirely (it is then rigid), never half of it; at least one is
//! required, and at least [`MIN_ROWS`] data rows. Every value must be a finite number; each
//! refusal names its line ([`FrfError`]).
//!
//! **Method** (per direction): least-squares complex frequency (LSCF, Guillaume et al. 2003),
//! the common-denominator rational fraction H(ω) ≈ B(z)/A(z) in z = e^(−iωΔt), Δt = 1/(2 f_max)
//! (polynomials on the unit circle, well conditioned where powers of iω are not), linearised as
//! B(z) − H A(z) = 0 with A monic and solved by least squares (Householder QR) on the
//! receptance scaled to its peak. The poles are the roots of A mapped by s = −ln z / Δt; a
//! pole is physical when it lies in the measured band with 0 < ζ < 0.5.
//!
//! **Number of modes: stabilisation diagram.** The fit is repeated for denominator orders
//! 2, 4, …, [`FitOptions::max_order`]. A physical pole of the highest order is a mode when a
//! chain of poles reaches down through the [`FitOptions::stable_orders`] orders below it,
//! each within [`FitOptions::frequency_tol`] in frequency and [`FitOptions::damping_tol`]
//! (relative) in damping of the next: noise and computational poles wander with the order,
//! structural poles stay.
//!
//! **Modal constants.** With the poles fixed, the receptance is fitted linearly by real
//! (normal) modes, H(ω) = Σ_k (1/k_k)·ω_k²/(ω_k² − ω² + 2iζ_k ω_k ω) + u − l·(ω₀/ω)², with an
//! upper residual u (modes above the band) and a lower residual l (below it, ω₀ the lowest
//! measured angular frequency). The mode shape is 1 at the tip (the crate's convention), so
//! k_k is the modal stiffness and m_k = k_k/ω_k² the modal mass. A mode with a non-positive
//! stiffness, or whose peak compliance 1/(2ζk) is under [`FitOptions::min_share`] of the
//! measured peak, is dropped and the constants refitted.
//!
//! Assumptions: one input and one output per direction (the direct receptances x/x and y/y,
//! no cross terms), light damping, real modes. Units SI; numerics only, no I/O.

mod parse;

pub use parse::{Frf, FrfError, MIN_ROWS};

use nalgebra::{Complex, DMatrix, DVector};
use thiserror::Error;

use crate::params::{Mode, TipModes};

/// Options of [`fit`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FitOptions {
    /// Highest denominator order of the stabilisation diagram (even; default 40, i.e. up to
    /// 20 pole pairs, enough for a few modes and the noise).
    pub max_order: usize,
    /// Orders below the highest through which a mode's pole must stay (default 6).
    pub stable_orders: usize,
    /// Largest relative change of a stable pole's frequency from one order to the next
    /// (default 0.01).
    pub frequency_tol: f64,
    /// Largest relative change of a stable pole's damping ratio from one order to the next
    /// (default 0.1).
    pub damping_tol: f64,
    /// Smallest peak compliance of a mode, relative to the measured peak (default 0.02).
    pub min_share: f64,
}

impl Default for FitOptions {
    fn default() -> Self {
        Self {
            max_order: 40,
            stable_orders: 6,
            frequency_tol: 0.01,
            damping_tol: 0.1,
            min_share: 0.02,
        }
    }
}

/// One fitted mode.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FittedMode {
    /// Natural frequency, damping ratio and modal stiffness (mode shape 1 at the tip).
    pub mode: Mode,
    /// Modal mass k/ω² in kg.
    pub modal_mass_kg: f64,
    /// Orders below the highest through which its pole stayed in the stabilisation diagram.
    pub stable_orders: usize,
}

/// The fit of one direction.
#[derive(Debug, Clone, PartialEq)]
pub struct DirectionFit {
    /// The modes, by frequency.
    pub modes: Vec<FittedMode>,
    /// Upper residual compliance u in m/N (modes above the band).
    pub upper_residual_m_per_n: f64,
    /// Lower residual l in m/N at the lowest measured frequency (modes below the band).
    pub lower_residual_m_per_n: f64,
    /// RMS of |H_measured − H_fitted| over the rows, m/N.
    pub rms_residual_m_per_n: f64,
    /// Largest measured |H| in m/N.
    pub peak_m_per_n: f64,
}

/// The fit of both directions (`None` for a direction the file does not have).
#[derive(Debug, Clone, PartialEq)]
pub struct ModalFit {
    /// Feed direction x.
    pub x: Option<DirectionFit>,
    /// Direction y.
    pub y: Option<DirectionFit>,
}

impl ModalFit {
    /// The fitted modes as the tip modes of a tool file (a direction without data is rigid).
    pub fn tip_modes(&self) -> TipModes {
        let modes = |d: &Option<DirectionFit>| {
            d.as_ref()
                .map(|d| d.modes.iter().map(|m| m.mode).collect())
                .unwrap_or_default()
        };
        TipModes {
            x: modes(&self.x),
            y: modes(&self.y),
        }
    }
}

/// Why a fit fails.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum FitError {
    /// An option is out of range.
    #[error("{name} must be {rule}, got {value}")]
    BadOption {
        /// The option.
        name: &'static str,
        /// What it must be.
        rule: &'static str,
        /// The value given.
        value: f64,
    },
    /// Fewer rows than the highest order needs unknowns.
    #[error("direction {direction}: {rows} rows are too few for model order {order} (need at least {need})")]
    TooFewRowsForOrder {
        /// `x` or `y`.
        direction: char,
        /// Rows.
        rows: usize,
        /// The highest order.
        order: usize,
        /// Rows needed.
        need: usize,
    },
    /// The receptance is zero everywhere.
    #[error("direction {direction}: the receptance is zero at every frequency")]
    ZeroReceptance {
        /// `x` or `y`.
        direction: char,
    },
    /// No pole passed the stabilisation criterion.
    #[error("direction {direction}: no stable mode in the band (try a higher max_order or fewer stable_orders)")]
    NoStableMode {
        /// `x` or `y`.
        direction: char,
    },
}

/// Fits the modes of every direction of `frf` (see the module doc).
///
/// # Errors
/// Bad options, too few rows for the highest order, a zero receptance, no stable mode.
pub fn fit(frf: &Frf, options: &FitOptions) -> Result<ModalFit, FitError> {
    let one = |data: &Option<Vec<(f64, f64)>>, direction| {
        data.as_ref()
            .map(|h| {
                let h: Vec<Complex<f64>> = h.iter().map(|&(re, im)| Complex::new(re, im)).collect();
                fit_direction(&frf.frequency_hz, &h, options, direction)
            })
            .transpose()
    };
    Ok(ModalFit {
        x: one(&frf.x_m_per_n, 'x')?,
        y: one(&frf.y_m_per_n, 'y')?,
    })
}

/// A physical pole: natural frequency (Hz) and damping ratio.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Pole {
    frequency_hz: f64,
    damping_ratio: f64,
}

/// Fits the modes of one direction from its receptance `h_m_per_n` at `frequency_hz`.
///
/// # Errors
/// As [`fit`].
pub fn fit_direction(
    frequency_hz: &[f64],
    h_m_per_n: &[Complex<f64>],
    options: &FitOptions,
    direction: char,
) -> Result<DirectionFit, FitError> {
    check_options(options)?;
    let rows = frequency_hz.len().min(h_m_per_n.len());
    let top = options.max_order;
    // 2·rows real equations for 2·top + 1 unknowns, with room to spare.
    let need = top + 1;
    if rows < need {
        return Err(FitError::TooFewRowsForOrder {
            direction,
            rows,
            order: top,
            need,
        });
    }
    let (f, h) = (&frequency_hz[..rows], &h_m_per_n[..rows]);
    let peak = h.iter().map(|v| v.norm()).fold(0.0, f64::max);
    if peak == 0.0 {
        return Err(FitError::ZeroReceptance { direction });
    }
    let scaled: Vec<Complex<f64>> = h.iter().map(|v| v / peak).collect();
    let band = (f[0], f[rows - 1]);
    let dt_s = 1.0 / (2.0 * band.1);
    let diagram: Vec<Vec<Pole>> = (1..=top / 2)
        .map(|k| lscf_poles(f, &scaled, 2 * k, dt_s, band))
        .collect();
    let stable = stable_poles(&diagram, options);
    if stable.is_empty() {
        return Err(FitError::NoStableMode { direction });
    }
    let mut kept = stable;
    loop {
        let poles: Vec<Pole> = kept.iter().map(|(p, _)| *p).collect();
        let constants = real_mode_constants(f, &scaled, &poles);
        // Drop the weakest of the unphysical or negligible modes, then refit the others.
        let share = |k: usize| constants.per_mode[k] / (2.0 * poles[k].damping_ratio);
        let weakest = (0..poles.len())
            .filter(|&k| constants.per_mode[k] <= 0.0 || share(k) < options.min_share)
            .min_by(|&a, &b| share(a).total_cmp(&share(b)));
        match weakest {
            Some(k) if kept.len() > 1 => {
                kept.remove(k);
            }
            Some(_) => return Err(FitError::NoStableMode { direction }),
            None => return Ok(constants.into_fit(&kept, h, peak)),
        }
    }
}

fn check_options(o: &FitOptions) -> Result<(), FitError> {
    let bad = |name, rule, value| Err(FitError::BadOption { name, rule, value });
    if o.max_order < 4 || o.max_order % 2 == 1 {
        return bad("max_order", "even and >= 4", o.max_order as f64);
    }
    if o.stable_orders == 0 || 2 * o.stable_orders >= o.max_order {
        return bad(
            "stable_orders",
            ">= 1 and below max_order / 2",
            o.stable_orders as f64,
        );
    }
    for (name, v) in [
        ("frequency_tol", o.frequency_tol),
        ("damping_tol", o.damping_tol),
        ("min_share", o.min_share),
    ] {
        if !(v.is_finite() && v > 0.0 && v < 1.0) {
            return bad(name, "in (0, 1)", v);
        }
    }
    Ok(())
}

/// Physical poles of the LSCF fit of denominator order `order`.
fn lscf_poles(
    f_hz: &[f64],
    h: &[Complex<f64>],
    order: usize,
    dt_s: f64,
    band: (f64, f64),
) -> Vec<Pole> {
    let n = order;
    let cols = 2 * n + 1;
    let mut j = DMatrix::zeros(2 * f_hz.len(), cols);
    let mut rhs = DVector::zeros(2 * f_hz.len());
    for (r, (&fk, &hk)) in f_hz.iter().zip(h).enumerate() {
        let z = Complex::from_polar(1.0, -2.0 * std::f64::consts::PI * fk * dt_s);
        let mut zj = Complex::new(1.0, 0.0);
        for c in 0..=n {
            // B part: b_c z^c; A part (c < n): −h a_c z^c; a_n = 1 goes to the right side.
            j[(2 * r, c)] = zj.re;
            j[(2 * r + 1, c)] = zj.im;
            let t = -hk * zj;
            if c < n {
                j[(2 * r, n + 1 + c)] = t.re;
                j[(2 * r + 1, n + 1 + c)] = t.im;
            } else {
                rhs[2 * r] = -t.re;
                rhs[2 * r + 1] = -t.im;
            }
            zj *= z;
        }
    }
    let Some(theta) = least_squares(j, rhs) else {
        return Vec::new();
    };
    // Companion matrix of the monic z^n + a_{n−1} z^{n−1} + … + a_0.
    let mut comp = DMatrix::zeros(n, n);
    for i in 0..n {
        comp[(0, i)] = -theta[n + 1 + (n - 1 - i)];
        if i + 1 < n {
            comp[(i + 1, i)] = 1.0;
        }
    }
    let mut poles: Vec<Pole> = comp
        .complex_eigenvalues()
        .iter()
        .filter_map(|z| {
            let s = -z.ln() / dt_s;
            let w = s.norm();
            let pole = Pole {
                frequency_hz: w / (2.0 * std::f64::consts::PI),
                damping_ratio: -s.re / w,
            };
            let physical = s.im > 0.0
                && pole.damping_ratio > 0.0
                && pole.damping_ratio < 0.5
                && pole.frequency_hz >= band.0
                && pole.frequency_hz <= band.1;
            physical.then_some(pole)
        })
        .collect();
    poles.sort_by(|a, b| a.frequency_hz.total_cmp(&b.frequency_hz));
    poles
}

/// Least squares by Householder QR with column scaling; `None` when rank deficient.
fn least_squares(mut j: DMatrix<f64>, rhs: DVector<f64>) -> Option<DVector<f64>> {
    let scale: Vec<f64> = j
        .column_iter()
        .map(|c| {
            let n = c.norm();
            if n > 0.0 {
                1.0 / n
            } else {
                1.0
            }
        })
        .collect();
    for (k, mut c) in j.column_iter_mut().enumerate() {
        c *= scale[k];
    }
    let qr = j.qr();
    let qtb = qr.q().transpose() * rhs;
    let r = qr.r();
    if r.diagonal().iter().any(|d| d.abs() < 1e-13) {
        return None;
    }
    let x = r.solve_upper_triangular(&qtb)?;
    Some(DVector::from_iterator(
        x.len(),
        x.iter().zip(&scale).map(|(v, s)| v * s),
    ))
}

/// The poles of the highest order that pass the stabilisation criterion, with the number of
/// orders below through which each stayed.
fn stable_poles(diagram: &[Vec<Pole>], o: &FitOptions) -> Vec<(Pole, usize)> {
    let Some((top, below)) = diagram.split_last() else {
        return Vec::new();
    };
    let near = |p: &Pole, q: &Pole| {
        (p.frequency_hz - q.frequency_hz).abs() <= o.frequency_tol * p.frequency_hz
            && (p.damping_ratio - q.damping_ratio).abs() <= o.damping_tol * p.damping_ratio
    };
    let mut out: Vec<(Pole, usize)> = Vec::new();
    for p in top {
        let mut current = *p;
        let mut depth = 0;
        for order in below.iter().rev() {
            let next = order.iter().filter(|q| near(&current, q)).min_by(|a, b| {
                let da = (a.frequency_hz - current.frequency_hz).abs();
                let db = (b.frequency_hz - current.frequency_hz).abs();
                da.total_cmp(&db)
            });
            match next {
                Some(q) => {
                    current = *q;
                    depth += 1;
                }
                None => break,
            }
        }
        // One mode per physical pole: a second top pole within the tolerance is a duplicate.
        let duplicate = out.iter().any(|(q, _)| near(p, q));
        if depth >= o.stable_orders && !duplicate {
            out.push((*p, depth));
        }
    }
    out
}

/// Real-mode constants of a fit with fixed poles, in units of the scaled receptance.
struct Constants {
    /// The static compliance 1/k_k of each mode, over the measured peak.
    per_mode: Vec<f64>,
    upper: f64,
    lower: f64,
    residual_rms: f64,
}

/// Linear least squares of the real-mode model with the poles fixed.
fn real_mode_constants(f_hz: &[f64], h: &[Complex<f64>], poles: &[Pole]) -> Constants {
    let nm = poles.len();
    let w0 = 2.0 * std::f64::consts::PI * f_hz[0].max(1e-3 * f_hz[f_hz.len() - 1]);
    let basis = |fk: f64| -> Vec<Complex<f64>> {
        let w = 2.0 * std::f64::consts::PI * fk;
        let mut b: Vec<Complex<f64>> = poles
            .iter()
            .map(|p| {
                let wn = 2.0 * std::f64::consts::PI * p.frequency_hz;
                let den = Complex::new(wn * wn - w * w, 2.0 * p.damping_ratio * wn * w);
                Complex::new(wn * wn, 0.0) / den
            })
            .collect();
        b.push(Complex::new(1.0, 0.0));
        b.push(Complex::new(-(w0 / w.max(1e-9)).powi(2), 0.0));
        b
    };
    let mut j = DMatrix::zeros(2 * f_hz.len(), nm + 2);
    let mut rhs = DVector::zeros(2 * f_hz.len());
    for (r, (&fk, &hk)) in f_hz.iter().zip(h).enumerate() {
        for (c, v) in basis(fk).iter().enumerate() {
            j[(2 * r, c)] = v.re;
            j[(2 * r + 1, c)] = v.im;
        }
        rhs[2 * r] = hk.re;
        rhs[2 * r + 1] = hk.im;
    }
    let x = least_squares(j, rhs).unwrap_or_else(|| DVector::zeros(nm + 2));
    let mut sq = 0.0;
    for (&fk, &hk) in f_hz.iter().zip(h) {
        let model: Complex<f64> = basis(fk).iter().zip(x.iter()).map(|(b, c)| b * *c).sum();
        sq += (hk - model).norm_sqr();
    }
    Constants {
        per_mode: x.iter().take(nm).copied().collect(),
        upper: x[nm],
        lower: x[nm + 1],
        residual_rms: (sq / f_hz.len() as f64).sqrt(),
    }
}

impl Constants {
    /// The fit in physical units (`peak` m/N per unit of the scaled receptance).
    fn into_fit(self, kept: &[(Pole, usize)], h: &[Complex<f64>], peak: f64) -> DirectionFit {
        let mut modes: Vec<FittedMode> = kept
            .iter()
            .zip(&self.per_mode)
            .map(|((p, depth), c)| {
                let stiffness = 1.0 / (c * peak);
                let mode = Mode {
                    frequency_hz: p.frequency_hz,
                    damping_ratio: p.damping_ratio,
                    stiffness_n_per_m: stiffness,
                };
                FittedMode {
                    modal_mass_kg: mode.modal_mass_kg(),
                    mode,
                    stable_orders: *depth,
                }
            })
            .collect();
        modes.sort_by(|a, b| a.mode.frequency_hz.total_cmp(&b.mode.frequency_hz));
        let measured_peak = h.iter().map(|v| v.norm()).fold(0.0, f64::max);
        DirectionFit {
            modes,
            upper_residual_m_per_n: self.upper * peak,
            lower_residual_m_per_n: self.lower * peak,
            rms_residual_m_per_n: self.residual_rms * peak,
            peak_m_per_n: measured_peak,
        }
    }
}

#[cfg(test)]
mod tests;
