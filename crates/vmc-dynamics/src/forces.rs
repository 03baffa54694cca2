//! Cutting-force geometry: engagement window, screen function and directional factors.
//!
//! Tooth angle φ is measured clockwise from the +y axis, the tool turns clockwise and
//! feeds along +x; tooth j sits at φ + 2πj/N. A tooth cuts when its angle lies in the
//! engagement window [φ_st, φ_ex] (the screen function g(φ) is 1 there, 0 elsewhere):
//! up milling φ_st = 0, φ_ex = arccos(1 − 2a_e/D); down milling φ_st = arccos(2a_e/D − 1),
//! φ_ex = π.
//!
//! Chip thickness h = f_z sinφ + (Δx sinφ + Δy cosφ) with Δ = q(t) − q(t−τ). Tangential and
//! normal forces F_t = K_t a_p h, F_n = K_n a_p h give, on the tool,
//! F_x = −F_t cosφ − F_n sinφ, F_y = F_t sinφ − F_n cosφ, so the dynamic force is
//! F = a_p·H(φ)·Δ with (per tooth, times g)
//!
//! ```text
//! H = [ −(K_t sc + K_n s²)   −(K_t c² + K_n sc) ]
//!     [   K_t s² − K_n sc      K_t sc − K_n c²  ]     s = sinφ, c = cosφ
//! ```
//!
//! Process damping adds F = −(C a_p / v_c)·D(φ)·q̇ with D = [s², sc; sc, c²] (the normal
//! penetration rate ẋ s + ẏ c resisted along the normal), v_c = πDn/60 the cutting speed.
//!
//! Helical teeth (helix angle β): the point of tooth j at height z above the tip is at angle
//! φ_j(z) = φ + 2πj/N − k_β z with the lag k_β = 2 tanβ / D. The flute is cut into K disks of
//! height a_p/K ([`Disks`], the axial discretisation of Altintas' textbook), each a straight
//! tooth at its mid-height lag, so a_p·H becomes (a_p/K)·Σ_k H(φ − k_β z_k). The mean over a
//! revolution does not depend on the lag, so the zero-order matrix A₀ is the same for every
//! helix angle.

use std::f64::consts::PI;

use nalgebra::Matrix2;

use crate::params::{validate_immersion, DynamicsError, Milling, Tool};

/// Angular window [entry, exit] in rad in which a tooth cuts.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Engagement {
    /// Entry angle φ_st in rad.
    pub entry_rad: f64,
    /// Exit angle φ_ex in rad.
    pub exit_rad: f64,
}

impl Engagement {
    /// Window for a radial immersion a_e/D in [0.01, 1] and a milling direction.
    pub fn new(immersion: f64, milling: Milling) -> Result<Self, DynamicsError> {
        validate_immersion(immersion)?;
        Ok(match milling {
            Milling::Up => Self {
                entry_rad: 0.0,
                exit_rad: (1.0 - 2.0 * immersion).clamp(-1.0, 1.0).acos(),
            },
            Milling::Down => Self {
                entry_rad: (2.0 * immersion - 1.0).clamp(-1.0, 1.0).acos(),
                exit_rad: PI,
            },
        })
    }

    /// Screen function g(φ): 1 inside the window (angle taken modulo 2π), else 0.
    pub fn screen(&self, phi_rad: f64) -> f64 {
        let p = phi_rad.rem_euclid(2.0 * PI);
        if p >= self.entry_rad && p <= self.exit_rad {
            1.0
        } else {
            0.0
        }
    }

    /// Calls `f(u, v)` on each part of [a, b] (b − a ≤ 2π) inside the window, in absolute angles.
    fn for_each_overlap(&self, a: f64, b: f64, mut f: impl FnMut(f64, f64)) {
        let shift = a.rem_euclid(2.0 * PI) - a;
        let (a0, b0) = (a + shift, b + shift);
        // [a0, b0] starts in [0, 2π) and is shorter than 2π, so two copies of the window suffice.
        for k in 0..2 {
            let off = 2.0 * PI * f64::from(k);
            let u = a0.max(self.entry_rad + off);
            let v = b0.min(self.exit_rad + off);
            if v > u {
                f(u - shift, v - shift);
            }
        }
    }
}

/// Windows in another frame of the feed plane.
impl Engagement {
    /// The same window seen from axes turned by `angle_rad` (counter-clockwise from +x): for a
    /// feed direction at `angle_rad` from the tip's x axis, a tooth at feed-frame angle φ sits at
    /// φ − `angle_rad` in the tip's frame, so the window shifts by −`angle_rad`. H(φ + π) = H(φ)
    /// and D(φ + π) = D(φ) (both are products of two unit vectors of φ), and a shift of the
    /// window is a shift of time, so the result is taken modulo π: entry in [0, π), exit below
    /// 2π, the range the screen and the step means handle.
    pub fn rotated(&self, angle_rad: f64) -> Self {
        let entry = self.entry_rad - angle_rad;
        let shift = (entry / PI).floor() * PI;
        Self {
            entry_rad: entry - shift,
            exit_rad: self.exit_rad - angle_rad - shift,
        }
    }
}

/// ∫ sin², ∫ cos², ∫ sin·cos over [u, v].
fn trig_integrals(u: f64, v: f64) -> (f64, f64, f64) {
    let d2 = ((2.0 * v).sin() - (2.0 * u).sin()) / 4.0;
    let ss = (v - u) / 2.0 - d2;
    let cc = (v - u) / 2.0 + d2;
    let sc = -((2.0 * v).cos() - (2.0 * u).cos()) / 4.0;
    (ss, cc, sc)
}

fn cutting_from(tool: &Tool, ss: f64, cc: f64, sc: f64) -> Matrix2<f64> {
    let (kt, kn) = (tool.kt_n_per_m2, tool.kn_n_per_m2);
    Matrix2::new(
        -(kt * sc + kn * ss),
        -(kt * cc + kn * sc),
        kt * ss - kn * sc,
        kt * sc - kn * cc,
    )
}

/// Instantaneous directional matrix H(φ) in N/m² (sum over teeth, screened); F = a_p·H·Δ.
pub fn cutting_matrix_at(tool: &Tool, window: &Engagement, phi_rad: f64) -> Matrix2<f64> {
    let mut h = Matrix2::zeros();
    for j in 0..tool.teeth {
        let p = phi_rad + 2.0 * PI * f64::from(j) / f64::from(tool.teeth);
        if window.screen(p) > 0.0 {
            let (s, c) = p.sin_cos();
            h += cutting_from(tool, s * s, c * c, s * c);
        }
    }
    h
}

/// Mean of H(φ) over the spindle-angle interval [φ_a, φ_b] (exact integral of the screened
/// trigonometric terms), in N/m².
pub fn cutting_matrix_mean(
    tool: &Tool,
    window: &Engagement,
    phi_a: f64,
    phi_b: f64,
) -> Matrix2<f64> {
    let (ss, cc, sc) = screened_integrals(tool, window, phi_a, phi_b);
    cutting_from(tool, ss, cc, sc) / (phi_b - phi_a)
}

/// Mean of the process-damping shape D(φ) = Σ g·[s², sc; sc, c²] over [φ_a, φ_b].
pub fn damping_matrix_mean(
    tool: &Tool,
    window: &Engagement,
    phi_a: f64,
    phi_b: f64,
) -> Matrix2<f64> {
    let (ss, cc, sc) = screened_integrals(tool, window, phi_a, phi_b);
    Matrix2::new(ss, sc, sc, cc) / (phi_b - phi_a)
}

fn screened_integrals(tool: &Tool, window: &Engagement, phi_a: f64, phi_b: f64) -> (f64, f64, f64) {
    let (mut ss, mut cc, mut sc) = (0.0, 0.0, 0.0);
    for j in 0..tool.teeth {
        let off = 2.0 * PI * f64::from(j) / f64::from(tool.teeth);
        window.for_each_overlap(phi_a + off, phi_b + off, |u, v| {
            let (a, b, c) = trig_integrals(u, v);
            ss += a;
            cc += b;
            sc += c;
        });
    }
    (ss, cc, sc)
}

/// Axial discretisation of a helical flute into disks of equal height.
#[derive(Debug, Clone, PartialEq)]
pub struct Disks {
    lags_rad: Vec<f64>,
}

impl Disks {
    /// Disks over an axial depth `depth_m` (m) such that neighbouring disks lag by at most
    /// `max_lag_rad`: K = ⌈k_β a_p / max_lag⌉ (at least 1), disk k at z_k = (k + ½) a_p / K.
    /// Straight teeth (or a zero depth) give one disk without lag, i.e. the straight-tooth model.
    pub fn new(tool: &Tool, depth_m: f64, max_lag_rad: f64) -> Self {
        let total = tool.lag_rad_per_m() * depth_m;
        if total <= 0.0 || !total.is_finite() || max_lag_rad <= 0.0 {
            return Self {
                lags_rad: vec![0.0],
            };
        }
        // The small allowance keeps K = m when the total lag is exactly m times the maximum
        // (rounding must not add a disk: see `helical_cutting_matrix_mean`).
        let count = ((total / max_lag_rad) - 1e-9).ceil().max(1.0) as usize;
        let lags_rad = (0..count)
            .map(|k| total * (k as f64 + 0.5) / count as f64)
            .collect();
        Self { lags_rad }
    }

    /// Number of disks K.
    pub fn count(&self) -> usize {
        self.lags_rad.len()
    }

    /// Lag angle k_β z_k of each disk in rad (0 for straight teeth).
    pub fn lags_rad(&self) -> &[f64] {
        &self.lags_rad
    }
}

/// Mean over [φ_a, φ_b] of the helical directional matrix (1/K)·Σ_k H(φ − k_β z_k) in N/m², so
/// that the force is a_p times it. With disks one step apart in lag and steps that tile the
/// tooth pitch, a depth of one axial pitch (k_β a_p = 2π/N) gives exactly A₀ at every step.
pub fn helical_cutting_matrix_mean(
    tool: &Tool,
    window: &Engagement,
    disks: &Disks,
    phi_a: f64,
    phi_b: f64,
) -> Matrix2<f64> {
    mean_over_disks(disks, |lag| {
        cutting_matrix_mean(tool, window, phi_a - lag, phi_b - lag)
    })
}

/// Mean over [φ_a, φ_b] of the helical process-damping shape (1/K)·Σ_k D(φ − k_β z_k).
pub fn helical_damping_matrix_mean(
    tool: &Tool,
    window: &Engagement,
    disks: &Disks,
    phi_a: f64,
    phi_b: f64,
) -> Matrix2<f64> {
    mean_over_disks(disks, |lag| {
        damping_matrix_mean(tool, window, phi_a - lag, phi_b - lag)
    })
}

/// The mean over the disks of `of(lag)`, each disk's matrix at its lag angle.
fn mean_over_disks(disks: &Disks, of: impl Fn(f64) -> Matrix2<f64>) -> Matrix2<f64> {
    let sum: Matrix2<f64> = disks.lags_rad().iter().map(|&lag| of(lag)).sum();
    sum / disks.count() as f64
}

/// Zero-order (time-averaged) directional matrix A₀ = (N/2π)∫_{φ_st}^{φ_ex} H dφ in N/m²
/// (the same for every helix angle).
pub fn average_cutting_matrix(tool: &Tool, window: &Engagement) -> Matrix2<f64> {
    cutting_matrix_mean(tool, window, 0.0, 2.0 * PI / f64::from(tool.teeth))
}

/// Cutting speed v_c = πDn/60 in m/s.
pub fn cutting_speed_m_per_s(tool: &Tool, spindle_rpm: f64) -> f64 {
    PI * tool.diameter_mm * 1e-3 * spindle_rpm / 60.0
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tool() -> Tool {
        Tool::new(2, 20.0, 6e8, 2e8)
    }

    #[test]
    fn slotting_average_is_minus_n_kn_over_four_in_xx() {
        let w = Engagement::new(1.0, Milling::Down).unwrap();
        let a0 = average_cutting_matrix(&tool(), &w);
        // Slotting: (N/2π)∫₀^π H dφ = (N/4)[−K_n, −K_t; K_t, −K_n].
        assert!((a0[(0, 0)] + 2.0 * 2e8 / 4.0).abs() < 1e-3);
        assert!((a0[(0, 1)] + 2.0 * 6e8 / 4.0).abs() < 1e-3);
        assert!((a0[(1, 0)] - 2.0 * 6e8 / 4.0).abs() < 1e-3);
        assert!((a0[(1, 1)] + 2.0 * 2e8 / 4.0).abs() < 1e-3);
    }

    #[test]
    fn mean_matches_quadrature_of_instantaneous() {
        let t = tool();
        let w = Engagement::new(0.3, Milling::Up).unwrap();
        let (a, b) = (0.2, 2.9);
        let n = 200_000;
        let mut q = Matrix2::zeros();
        for i in 0..n {
            let p = a + (b - a) * (i as f64 + 0.5) / n as f64;
            q += cutting_matrix_at(&t, &w, p);
        }
        q /= n as f64;
        let m = cutting_matrix_mean(&t, &w, a, b);
        assert!((q - m).norm() / m.norm() < 1e-4, "{q} vs {m}");
    }

    #[test]
    fn windows_for_up_and_down() {
        let up = Engagement::new(0.5, Milling::Up).unwrap();
        assert!((up.exit_rad - PI / 2.0).abs() < 1e-12 && up.entry_rad == 0.0);
        let down = Engagement::new(0.05, Milling::Down).unwrap();
        assert!((down.entry_rad - (-0.9f64).acos()).abs() < 1e-12 && down.exit_rad == PI);
    }

    #[test]
    fn a_rotated_window_keeps_its_width_and_stays_in_range() {
        let w = Engagement::new(0.3, Milling::Down).unwrap();
        for angle in [-7.0, -PI / 2.0, 0.0, 0.4, PI, 5.0] {
            let r = w.rotated(angle);
            assert!((0.0..PI).contains(&r.entry_rad), "{angle}: {r:?}");
            assert!(r.exit_rad < 2.0 * PI);
            assert!(((r.exit_rad - r.entry_rad) - (w.exit_rad - w.entry_rad)).abs() < 1e-12);
            // The shift is −angle modulo π.
            let k = (r.entry_rad - (w.entry_rad - angle)) / PI;
            assert!((k - k.round()).abs() < 1e-9, "{angle}: {k}");
        }
    }
}
