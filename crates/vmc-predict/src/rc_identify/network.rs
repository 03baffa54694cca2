//! The identified network and its forward model (the twin's implicit-Euler step, on the data's
//! own time steps).

/// W per (1000 rpm · N·mm) of bearing friction: `H = 2π/60 000 · n · M` with `n` in rpm, so a
/// heat input of `a` W per 1000 rpm is a friction torque of `a / BEARING_W_PER_KRPM_N_MM` N·mm.
pub const BEARING_W_PER_KRPM_N_MM: f64 = std::f64::consts::TAU / 60.0;

/// A chain network of 1 to 3 nodes (SI units; heat input in W).
///
/// Node 0 receives the spindle's heat; node `i` is linked to node `i + 1`; every node is
/// linked to the ambient, node 0 through a conductance that grows with the speed.
#[derive(Debug, Clone, PartialEq)]
pub struct RcNetwork {
    /// Heat capacity of each node, J/K.
    pub capacity_j_per_k: Vec<f64>,
    /// Conductance of the link between node `i` and node `i + 1`, W/K (one fewer than nodes).
    pub link_w_per_k: Vec<f64>,
    /// Conductance of each node to ambient at rest, W/K.
    pub ambient_w_per_k: Vec<f64>,
    /// Growth of node 0's conductance to ambient per 1000 rpm: `hA(n) = hA₀·(1 + γ·n/1000)`
    /// (the twin's `ha_gain_per_krpm`), ≥ 0.
    pub ha_gain_per_krpm: f64,
    /// Heat input into node 0 per 1000 rpm, W (`a` of `q = a·k + b·k²`, k = |n|/1000 rpm).
    pub heat_w_per_krpm: f64,
    /// Heat input into node 0 per (1000 rpm)², W (`b`).
    pub heat_w_per_krpm2: f64,
}

impl RcNetwork {
    /// Number of nodes.
    #[must_use]
    pub fn nodes(&self) -> usize {
        self.capacity_j_per_k.len()
    }

    /// Heat input into node 0 at `rpm`, W.
    #[must_use]
    pub fn heat_w(&self, rpm: f64) -> f64 {
        let k = rpm.abs() / 1000.0;
        self.heat_w_per_krpm * k + self.heat_w_per_krpm2 * k * k
    }

    /// Whether the sizes agree (nodes 1…3, one link fewer) and every value is finite and
    /// positive (heat and γ non-negative).
    #[must_use]
    pub fn is_valid(&self) -> bool {
        let n = self.nodes();
        let pos = |v: &[f64]| v.iter().all(|x| x.is_finite() && *x > 0.0);
        let nonneg = |x: f64| x.is_finite() && x >= 0.0;
        (1..=3).contains(&n)
            && self.link_w_per_k.len() == n - 1
            && self.ambient_w_per_k.len() == n
            && pos(&self.capacity_j_per_k)
            && pos(&self.link_w_per_k)
            && pos(&self.ambient_w_per_k)
            && nonneg(self.ha_gain_per_krpm)
            && nonneg(self.heat_w_per_krpm)
            && nonneg(self.heat_w_per_krpm2)
    }

    /// Absolute node temperatures (°C) of every row, one `Vec` per node, from every node at
    /// `ambient_degc[0]` on the first row. Step `r − 1 → r` holds the speed of row `r − 1` and
    /// takes the ambient of row `r` (as the twin's `ThermalNetwork::step` with that activity and
    /// ambient): `(C/dt + K + H(n))·T⁺ = C/dt·T + q(n)·e₀ + H(n)·T_a`.
    #[must_use]
    pub fn simulate(&self, time_s: &[f64], rpm: &[f64], ambient_degc: &[f64]) -> Vec<Vec<f64>> {
        let n = self.nodes();
        let rows = time_s.len().min(rpm.len()).min(ambient_degc.len());
        let mut out = vec![Vec::with_capacity(rows); n];
        let Some(&a0) = ambient_degc.first() else {
            return out;
        };
        let mut t = vec![a0; n];
        for (i, o) in out.iter_mut().enumerate() {
            o.push(t[i]);
        }
        // Tridiagonal system, solved by the Thomas algorithm.
        let (mut diag, mut rhs, mut c_prime) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
        for r in 1..rows {
            let dt = time_s[r] - time_s[r - 1];
            let k = rpm[r - 1].abs() / 1000.0;
            let ta = ambient_degc[r];
            for i in 0..n {
                let mut h = self.ambient_w_per_k[i];
                if i == 0 {
                    h *= 1.0 + self.ha_gain_per_krpm * k;
                }
                let left = if i > 0 { self.link_w_per_k[i - 1] } else { 0.0 };
                let right = if i + 1 < n { self.link_w_per_k[i] } else { 0.0 };
                let c_dt = self.capacity_j_per_k[i] / dt;
                diag[i] = c_dt + h + left + right;
                rhs[i] = c_dt * t[i] + h * ta;
            }
            rhs[0] += self.heat_w(rpm[r - 1]);
            // Forward sweep: the off-diagonal of rows i and i+1 is −link[i].
            let mut d_prev = diag[0];
            c_prime[0] = if n > 1 {
                -self.link_w_per_k[0] / d_prev
            } else {
                0.0
            };
            rhs[0] /= d_prev;
            for i in 1..n {
                let sub = -self.link_w_per_k[i - 1];
                d_prev = diag[i] - sub * c_prime[i - 1];
                c_prime[i] = if i + 1 < n {
                    -self.link_w_per_k[i] / d_prev
                } else {
                    0.0
                };
                rhs[i] = (rhs[i] - sub * rhs[i - 1]) / d_prev;
            }
            t[n - 1] = rhs[n - 1];
            for i in (0..n - 1).rev() {
                t[i] = rhs[i] - c_prime[i] * t[i + 1];
            }
            for (i, o) in out.iter_mut().enumerate() {
                o.push(t[i]);
            }
        }
        out
    }
}
