//! Grey-box identification of a two-node thermal RC network from a spindle thermal test
//! (numerical core only: no files, no printing).
//!
//! Network: node 1 (the spindle's bearings) receives the heat input `q(n) = a·n/1000 + b·(n/1000)²`
//! W of the spindle speed `n` (rpm); node 2 (the headstock) is linked to node 1 and both are
//! linked to the ambient temperature `T_a(t)` (a measured column or a constant):
//!
//! ```text
//! C₁·dT₁/dt = q(n) − G₁₂·(T₁ − T₂) − G₁ₐ·(T₁ − T_a)
//! C₂·dT₂/dt = G₁₂·(T₁ − T₂) − G₂ₐ·(T₂ − T_a)
//! ```
//!
//! integrated by implicit Euler on the data's own time steps, starting at the ambient
//! temperature (the machine at rest when the file starts). Each drift channel is a linear
//! combination `d_k = c_k0 + c_k1·(T₁ − T_a) + c_k2·(T₂ − T_a)`, solved by least squares for given
//! network parameters (variable projection). The network parameters (log capacities and
//! conductances, `a`, `b`) are fitted by Levenberg–Marquardt on the drift residuals, each channel
//! scaled by its standard deviation, and, where a measured temperature is given for a node, on
//! that node's temperature residual too: without one, heat input and drift gains trade off and
//! only their products are identified.

use nalgebra::{DMatrix, DVector};

/// The identified network (SI units; heat input in W).
#[derive(Debug, Clone, PartialEq)]
pub struct RcNetwork {
    /// Heat capacities of nodes 1 and 2, J/K.
    pub capacity_j_per_k: [f64; 2],
    /// Conductance between nodes 1 and 2, W/K.
    pub g12_w_per_k: f64,
    /// Conductances of nodes 1 and 2 to ambient, W/K.
    pub g_ambient_w_per_k: [f64; 2],
    /// Heat input per 1000 rpm, W (`a`).
    pub heat_w_per_krpm: f64,
    /// Heat input per (1000 rpm)², W (`b`).
    pub heat_w_per_krpm2: f64,
}

impl RcNetwork {
    /// A starting point: time constants of about 1 h and 4 h, a few tens of W at 5000 rpm.
    pub fn initial_guess() -> Self {
        Self {
            capacity_j_per_k: [36_000.0, 288_000.0],
            g12_w_per_k: 10.0,
            g_ambient_w_per_k: [5.0, 20.0],
            heat_w_per_krpm: 5.0,
            heat_w_per_krpm2: 1.0,
        }
    }

    fn to_params(&self) -> Vec<f64> {
        vec![
            self.capacity_j_per_k[0].ln(),
            self.capacity_j_per_k[1].ln(),
            self.g12_w_per_k.ln(),
            self.g_ambient_w_per_k[0].ln(),
            self.g_ambient_w_per_k[1].ln(),
            self.heat_w_per_krpm,
            self.heat_w_per_krpm2,
        ]
    }

    fn from_params(p: &[f64]) -> Self {
        Self {
            capacity_j_per_k: [p[0].exp(), p[1].exp()],
            g12_w_per_k: p[2].exp(),
            g_ambient_w_per_k: [p[3].exp(), p[4].exp()],
            heat_w_per_krpm: p[5],
            heat_w_per_krpm2: p[6],
        }
    }

    /// Node temperature rises above ambient, `[T₁ − T_a, T₂ − T_a]` per row.
    pub fn simulate(&self, time_s: &[f64], rpm: &[f64], ambient_degc: &[f64]) -> Vec<[f64; 2]> {
        let [c1, c2] = self.capacity_j_per_k;
        let [g1a, g2a] = self.g_ambient_w_per_k;
        let g12 = self.g12_w_per_k;
        let mut t = match ambient_degc.first() {
            Some(a) => [*a, *a],
            None => return Vec::new(),
        };
        let mut out = Vec::with_capacity(time_s.len());
        out.push([0.0, 0.0]);
        for r in 1..time_s.len().min(rpm.len()).min(ambient_degc.len()) {
            let dt = time_s[r] - time_s[r - 1];
            let k = rpm[r - 1].abs() / 1000.0;
            let q = self.heat_w_per_krpm * k + self.heat_w_per_krpm2 * k * k;
            let ta = ambient_degc[r];
            // (C/dt + G)·T_new = C/dt·T_old + sources, a 2×2 system.
            let (a11, a12) = (c1 / dt + g12 + g1a, -g12);
            let (a21, a22) = (-g12, c2 / dt + g12 + g2a);
            let b1 = c1 / dt * t[0] + q + g1a * ta;
            let b2 = c2 / dt * t[1] + g2a * ta;
            let det = a11 * a22 - a12 * a21;
            t = [(b1 * a22 - a12 * b2) / det, (a11 * b2 - a21 * b1) / det];
            out.push([t[0] - ta, t[1] - ta]);
        }
        out
    }
}

/// What the identification fits.
pub struct RcData<'a> {
    /// Time of each row, s (strictly increasing).
    pub time_s: &'a [f64],
    /// Spindle speed, rpm.
    pub rpm: &'a [f64],
    /// Ambient temperature, °C.
    pub ambient_degc: &'a [f64],
    /// Drift channels, one column each.
    pub drifts: &'a [Vec<f64>],
    /// Measured temperatures of nodes 1 and 2 (°C), where known.
    pub node_temps: [Option<&'a [f64]>; 2],
}

/// An identified network with its drift gains.
#[derive(Debug, Clone, PartialEq)]
pub struct RcFit {
    /// The network.
    pub network: RcNetwork,
    /// Per channel `[c_k0, c_k1, c_k2]`: offset (µm, or the drift's unit) and gains per K of
    /// node 1 and node 2 above ambient.
    pub drift_gains: Vec<[f64; 3]>,
    /// Levenberg–Marquardt iterations taken.
    pub iterations: usize,
}

impl RcFit {
    /// Predicted drifts (one column per channel) of every row.
    pub fn predict(&self, time_s: &[f64], rpm: &[f64], ambient_degc: &[f64]) -> Vec<Vec<f64>> {
        let rise = self.network.simulate(time_s, rpm, ambient_degc);
        self.drift_gains
            .iter()
            .map(|c| {
                rise.iter()
                    .map(|x| c[0] + c[1] * x[0] + c[2] * x[1])
                    .collect()
            })
            .collect()
    }
}

/// Why the identification failed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum RcError {
    /// Columns of different lengths, too few rows or no drift channel.
    #[error("identify: {0}")]
    BadData(String),
    /// A value or the fit is not finite.
    #[error("identify: the fit diverged (non-finite residuals)")]
    Diverged,
}

/// Drift gains by least squares on `rows`, and the scaled residual vector.
fn residuals(
    net: &RcNetwork,
    data: &RcData,
    rows: &[usize],
    scales: &[f64],
) -> Option<(Vec<f64>, Vec<[f64; 3]>)> {
    let rise = net.simulate(data.time_s, data.rpm, data.ambient_degc);
    if rise.len() != data.time_s.len() {
        return None;
    }
    let x = DMatrix::from_fn(rows.len(), 3, |i, j| match j {
        0 => 1.0,
        _ => rise[rows[i]][j - 1],
    });
    let svd = x.clone().svd(true, true);
    let mut res = Vec::with_capacity(rows.len() * (data.drifts.len() + 2));
    let mut gains = Vec::with_capacity(data.drifts.len());
    for (k, d) in data.drifts.iter().enumerate() {
        let y = DVector::from_iterator(rows.len(), rows.iter().map(|&r| d[r]));
        let c = svd.solve(&y, 1e-12).ok()?;
        let fit = &x * &c;
        res.extend((0..rows.len()).map(|i| (y[i] - fit[i]) / scales[k]));
        gains.push([c[0], c[1], c[2]]);
    }
    for (n, temps) in data.node_temps.iter().enumerate() {
        if let Some(t) = temps {
            let s = scales[data.drifts.len() + n];
            res.extend(
                rows.iter()
                    .map(|&r| (t[r] - data.ambient_degc[r] - rise[r][n]) / s),
            );
        }
    }
    res.iter().all(|v| v.is_finite()).then_some((res, gains))
}

/// Standard deviation over `rows` (1 if zero).
fn sd(v: &[f64], rows: &[usize]) -> f64 {
    let n = rows.len().max(1) as f64;
    let m = rows.iter().map(|&r| v[r]).sum::<f64>() / n;
    let s = (rows.iter().map(|&r| (v[r] - m).powi(2)).sum::<f64>() / n).sqrt();
    if s > 0.0 {
        s
    } else {
        1.0
    }
}

/// Identifies the network and drift gains on `rows` (the simulation runs over every row, so the
/// state carries the history of rows not fitted), from `start`, with at most `max_iter`
/// Levenberg–Marquardt iterations. Deterministic.
///
/// # Errors
/// [`RcError::BadData`] for inconsistent columns or fewer than 10 fitting rows;
/// [`RcError::Diverged`] when the starting point already gives non-finite residuals.
pub fn identify(
    data: &RcData,
    rows: &[usize],
    start: &RcNetwork,
    max_iter: usize,
) -> Result<RcFit, RcError> {
    let n = data.time_s.len();
    let lens_ok = data.rpm.len() == n
        && data.ambient_degc.len() == n
        && data.drifts.iter().all(|d| d.len() == n)
        && data.node_temps.iter().flatten().all(|t| t.len() == n);
    if !lens_ok || data.drifts.is_empty() || rows.len() < 10 || rows.iter().any(|&r| r >= n) {
        return Err(RcError::BadData(format!(
            "need equally long columns, at least one drift channel and 10 fitting rows \
             ({n} rows, {} drift channels, {} fitting rows)",
            data.drifts.len(),
            rows.len()
        )));
    }
    if data
        .time_s
        .windows(2)
        .any(|w| w[1].partial_cmp(&w[0]) != Some(std::cmp::Ordering::Greater))
    {
        return Err(RcError::BadData("time must increase strictly".into()));
    }
    let scales: Vec<f64> = data
        .drifts
        .iter()
        .map(|d| sd(d, rows))
        .chain(
            data.node_temps
                .iter()
                .map(|t| t.map_or(1.0, |t| sd(t, rows))),
        )
        .collect();
    let cost = |p: &[f64]| {
        residuals(&RcNetwork::from_params(p), data, rows, &scales)
            .map(|(r, g)| (r.iter().map(|v| v * v).sum::<f64>(), r, g))
    };
    let mut p = start.to_params();
    let (mut c0, mut r0, mut g0) = cost(&p).ok_or(RcError::Diverged)?;
    let mut mu = 1e-2;
    let mut iterations = 0;
    for _ in 0..max_iter {
        iterations += 1;
        // Forward-difference Jacobian.
        let m = r0.len();
        let mut jac = DMatrix::<f64>::zeros(m, p.len());
        for j in 0..p.len() {
            let h = 1e-6 * p[j].abs().max(1.0);
            let mut q = p.clone();
            q[j] += h;
            let Some((_, rj, _)) = cost(&q) else {
                continue;
            };
            for i in 0..m {
                jac[(i, j)] = (rj[i] - r0[i]) / h;
            }
        }
        let jt = jac.transpose();
        let jtj = &jt * &jac;
        let g = &jt * DVector::from_vec(r0.clone());
        let mut improved = false;
        for _ in 0..10 {
            let mut a = jtj.clone();
            for d in 0..p.len() {
                a[(d, d)] += mu * jtj[(d, d)].max(1e-12);
            }
            let Some(step) = a.lu().solve(&(-&g)) else {
                mu *= 10.0;
                continue;
            };
            let q: Vec<f64> = p.iter().zip(step.iter()).map(|(a, b)| a + b).collect();
            match cost(&q) {
                Some((c, r, gains)) if c < c0 => {
                    let done = (c0 - c) <= 1e-10 * c0;
                    (p, c0, r0, g0) = (q, c, r, gains);
                    mu = (mu / 3.0).max(1e-12);
                    improved = !done;
                    break;
                }
                _ => mu *= 10.0,
            }
        }
        if !improved {
            break;
        }
    }
    Ok(RcFit {
        network: RcNetwork::from_params(&p),
        drift_gains: g0,
        iterations,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Three 4 h on / 4 h off cycles at rising speeds, one row a minute, ambient 20 °C with a
    /// slow wave.
    fn test_series() -> (Vec<f64>, Vec<f64>, Vec<f64>) {
        let t: Vec<f64> = (0..1440).map(|i| 60.0 * f64::from(i)).collect();
        let rpm = (0..1440)
            .map(|i| {
                if (i % 480) < 240 {
                    1250.0 * f64::from(i / 480 + 1)
                } else {
                    0.0
                }
            })
            .collect();
        let amb = t
            .iter()
            .map(|s| 20.0 + 0.5 * (s / 20_000.0).sin())
            .collect();
        (t, rpm, amb)
    }

    #[test]
    fn a_network_is_recovered_from_its_own_drifts_and_node_temperature() {
        let (t, rpm, amb) = test_series();
        let truth = RcNetwork {
            capacity_j_per_k: [20_000.0, 400_000.0],
            g12_w_per_k: 6.0,
            g_ambient_w_per_k: [3.0, 30.0],
            heat_w_per_krpm: 8.0,
            heat_w_per_krpm2: 2.0,
        };
        let rise = truth.simulate(&t, &rpm, &amb);
        let drifts: Vec<Vec<f64>> = [[0.5, 2.0, -1.0], [0.0, -0.7, 3.0]]
            .iter()
            .map(|c| {
                rise.iter()
                    .map(|x| c[0] + c[1] * x[0] + c[2] * x[1])
                    .collect()
            })
            .collect();
        let t1: Vec<f64> = rise.iter().zip(&amb).map(|(x, a)| a + x[0]).collect();
        let data = RcData {
            time_s: &t,
            rpm: &rpm,
            ambient_degc: &amb,
            drifts: &drifts,
            node_temps: [Some(&t1), None],
        };
        // Fit on the first two cycles, predict the third.
        let rows: Vec<usize> = (0..960).collect();
        let fit = identify(&data, &rows, &RcNetwork::initial_guess(), 200).unwrap();
        let pred = fit.predict(&t, &rpm, &amb);
        for (k, d) in drifts.iter().enumerate() {
            let rms = |f: &dyn Fn(usize) -> f64| {
                ((960..1440).map(|r| f(r).powi(2)).sum::<f64>() / 480.0).sqrt()
            };
            let raw = rms(&|r| d[r]);
            let err = rms(&|r| pred[k][r] - d[r]);
            assert!(err < 0.02 * raw, "channel {k}: {err} vs raw {raw}, {fit:?}");
        }
    }

    #[test]
    fn inconsistent_columns_are_errors_not_panics() {
        let (t, rpm, amb) = test_series();
        let short = vec![vec![0.0; 10]];
        let data = RcData {
            time_s: &t,
            rpm: &rpm,
            ambient_degc: &amb,
            drifts: &short,
            node_temps: [None, None],
        };
        let rows: Vec<usize> = (0..100).collect();
        let e = identify(&data, &rows, &RcNetwork::initial_guess(), 5).unwrap_err();
        assert!(e.to_string().contains("equally long columns"), "{e}");
    }
}
