//! The multilayer perceptron: forward pass, analytic Jacobian (backprop) and initialisation.
//!
//! Layer `l` maps `a_l` (width `sizes[l]`) to `a_{l+1} = φ(W_l a_l + b_l)` with `φ = tanh` (std
//! or the fast approximation, see [`Activation`]) on hidden layers and the identity on the
//! output layer. Weights are one flat `Vec<f64>`: for each layer in order, `W_l` row-major (`sizes[l+1]` rows × `sizes[l]` columns) followed by `b_l`.

use rand::rngs::StdRng;
use rand::{RngExt, SeedableRng};
use serde::{Deserialize, Serialize};

use super::activation::Activation;
use super::NnError;

/// How initial weights are drawn.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum Init {
    /// Glorot/Xavier uniform `U(±√(6/(fan_in + fan_out)))` for every layer, zero biases.
    Xavier,
    /// Nguyen–Widrow for the first hidden layer (rows of norm `0.7·H^(1/n_in)`, biases spread
    /// over the same range, so the tanh "active regions" tile the normalised input space),
    /// Xavier for the later layers. The default: it makes LM converge from more seeds.
    #[default]
    NguyenWidrow,
}

/// A tanh multilayer perceptron with a linear output layer.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "MlpData", into = "MlpData")]
pub struct Mlp {
    sizes: Vec<usize>,
    weights: Vec<f64>,
    activation: Activation,
}

/// The serialised form of [`Mlp`], validated on the way in.
#[derive(Serialize, Deserialize)]
struct MlpData {
    /// Layer widths: inputs, hidden layers…, outputs.
    sizes: Vec<usize>,
    /// Flat weights (layout in the module doc).
    weights: Vec<f64>,
    /// Hidden-layer activation (absent in older files: std tanh).
    #[serde(default)]
    activation: Activation,
}

impl TryFrom<MlpData> for Mlp {
    type Error = NnError;
    fn try_from(d: MlpData) -> Result<Self, NnError> {
        Ok(Mlp::from_weights(&d.sizes, d.weights)?.with_activation(d.activation))
    }
}

impl From<Mlp> for MlpData {
    fn from(m: Mlp) -> Self {
        MlpData {
            sizes: m.sizes,
            weights: m.weights,
            activation: m.activation,
        }
    }
}

impl Mlp {
    /// A net with the given layer widths (`[n_in, hidden…, n_out]`) and all weights zero.
    pub fn zeros(sizes: &[usize]) -> Result<Self, NnError> {
        check_sizes(sizes)?;
        Ok(Self {
            sizes: sizes.to_vec(),
            weights: vec![0.0; param_count(sizes)],
            activation: Activation::Tanh,
        })
    }

    /// A net with the given widths and weights (layout in the module doc); weights must be finite.
    pub fn from_weights(sizes: &[usize], weights: Vec<f64>) -> Result<Self, NnError> {
        check_sizes(sizes)?;
        let expected = param_count(sizes);
        if weights.len() != expected {
            return Err(NnError::BufferLength {
                buffer: "weights",
                expected,
                got: weights.len(),
            });
        }
        if let Some(index) = weights.iter().position(|w| !w.is_finite()) {
            return Err(NnError::NonFiniteWeight { index });
        }
        Ok(Self {
            sizes: sizes.to_vec(),
            weights,
            activation: Activation::Tanh,
        })
    }

    /// A randomly initialised net; the same `seed` always gives bit-identical weights.
    pub fn random(sizes: &[usize], init: Init, seed: u64) -> Result<Self, NnError> {
        let mut mlp = Self::zeros(sizes)?;
        let mut rng = StdRng::seed_from_u64(seed);
        let n_layers = sizes.len() - 1;
        let mut off = 0;
        for l in 0..n_layers {
            let (n_i, n_o) = (sizes[l], sizes[l + 1]);
            let (w, rest) = mlp.weights[off..].split_at_mut(n_i * n_o);
            let b = &mut rest[..n_o];
            let nguyen_widrow = init == Init::NguyenWidrow && l == 0 && n_layers > 1;
            if nguyen_widrow {
                let beta = 0.7 * (n_o as f64).powf(1.0 / n_i as f64);
                for row in w.chunks_exact_mut(n_i) {
                    row.iter_mut()
                        .for_each(|v| *v = rng.random_range(-1.0..1.0));
                    let norm = row.iter().map(|v| v * v).sum::<f64>().sqrt().max(1e-12);
                    row.iter_mut().for_each(|v| *v *= beta / norm);
                }
                b.iter_mut()
                    .for_each(|v| *v = rng.random_range(-beta..beta));
            } else {
                let limit = (6.0 / (n_i + n_o) as f64).sqrt();
                w.iter_mut()
                    .for_each(|v| *v = rng.random_range(-limit..limit));
            }
            off += n_i * n_o + n_o;
        }
        Ok(mlp)
    }

    /// The same net with another hidden-layer activation (weights unchanged).
    #[must_use]
    pub fn with_activation(mut self, activation: Activation) -> Self {
        self.activation = activation;
        self
    }

    /// The hidden-layer activation.
    pub fn activation(&self) -> Activation {
        self.activation
    }

    /// Layer widths `[n_in, hidden…, n_out]`.
    pub fn sizes(&self) -> &[usize] {
        &self.sizes
    }

    /// Number of inputs.
    pub fn n_in(&self) -> usize {
        self.sizes[0]
    }

    /// Number of outputs.
    pub fn n_out(&self) -> usize {
        self.sizes[self.sizes.len() - 1]
    }

    /// Number of weights and biases.
    pub fn n_params(&self) -> usize {
        self.weights.len()
    }

    /// The flat weights (layout in the module doc).
    pub fn weights(&self) -> &[f64] {
        &self.weights
    }

    /// Replaces all weights (same count required; values must be finite).
    pub fn set_weights(&mut self, weights: &[f64]) -> Result<(), NnError> {
        if weights.len() != self.weights.len() {
            return Err(NnError::BufferLength {
                buffer: "weights",
                expected: self.weights.len(),
                got: weights.len(),
            });
        }
        if let Some(index) = weights.iter().position(|w| !w.is_finite()) {
            return Err(NnError::NonFiniteWeight { index });
        }
        self.weights.copy_from_slice(weights);
        Ok(())
    }

    /// Length of the scratch buffer [`Mlp::forward_into`] needs: twice the widest hidden layer.
    pub fn scratch_len(&self) -> usize {
        2 * self.max_hidden()
    }

    /// Length of the work buffer [`Mlp::jacobian_into`] needs.
    pub fn jacobian_work_len(&self) -> usize {
        let hidden: usize = self.sizes[1..self.sizes.len() - 1].iter().sum();
        let widest = self.sizes.iter().copied().max().unwrap_or(0);
        hidden + 2 * widest
    }

    /// Forward pass without allocation: `out = net(x)`.
    ///
    /// `x.len() == n_in()`, `out.len() == n_out()`, `scratch.len() >= scratch_len()`.
    pub fn forward_into(
        &self,
        x: &[f64],
        scratch: &mut [f64],
        out: &mut [f64],
    ) -> Result<(), NnError> {
        self.check_len("input", x.len(), self.n_in())?;
        self.check_len("output", out.len(), self.n_out())?;
        if scratch.len() < self.scratch_len() {
            return Err(NnError::BufferLength {
                buffer: "scratch",
                expected: self.scratch_len(),
                got: scratch.len(),
            });
        }
        self.forward_unchecked(x, scratch, out);
        Ok(())
    }

    /// Forward pass that allocates its buffers (convenience; use `forward_into` in loops).
    pub fn forward(&self, x: &[f64]) -> Result<Vec<f64>, NnError> {
        let mut out = vec![0.0; self.n_out()];
        let mut scratch = vec![0.0; self.scratch_len()];
        self.forward_into(x, &mut scratch, &mut out)?;
        Ok(out)
    }

    /// Outputs and their Jacobian with respect to the weights, by backpropagation.
    ///
    /// `jac` is `n_out × n_params` row-major: `jac[k·P + p] = ∂y_k/∂w_p`.
    /// `work.len() >= jacobian_work_len()`.
    pub fn jacobian_into(
        &self,
        x: &[f64],
        work: &mut [f64],
        y: &mut [f64],
        jac: &mut [f64],
    ) -> Result<(), NnError> {
        self.check_len("input", x.len(), self.n_in())?;
        self.check_len("output", y.len(), self.n_out())?;
        self.check_len("jacobian", jac.len(), self.n_out() * self.n_params())?;
        if work.len() < self.jacobian_work_len() {
            return Err(NnError::BufferLength {
                buffer: "jacobian work",
                expected: self.jacobian_work_len(),
                got: work.len(),
            });
        }
        self.jacobian_unchecked(x, work, y, jac);
        Ok(())
    }

    /// Forward pass with lengths already checked (the hot path of training and prediction).
    pub(crate) fn forward_unchecked(&self, x: &[f64], scratch: &mut [f64], out: &mut [f64]) {
        let n_layers = self.sizes.len() - 1;
        let (buf_a, buf_b) = scratch.split_at_mut(self.max_hidden());
        let mut off = 0;
        for l in 0..n_layers {
            let (n_i, n_o) = (self.sizes[l], self.sizes[l + 1]);
            let w = &self.weights[off..off + n_i * n_o + n_o];
            off += n_i * n_o + n_o;
            // Even layers write buf_a, odd layers buf_b; each reads what the previous one wrote.
            if l + 1 == n_layers {
                let prev: &[f64] = match (l, l % 2) {
                    (0, _) => x,
                    (_, 1) => &buf_a[..n_i],
                    _ => &buf_b[..n_i],
                };
                dense(w, prev, &mut out[..n_o], |s| s);
            } else if l % 2 == 0 {
                let prev: &[f64] = if l == 0 { x } else { &buf_b[..n_i] };
                self.dense_hidden(w, prev, &mut buf_a[..n_o]);
            } else {
                self.dense_hidden(w, &buf_a[..n_i], &mut buf_b[..n_o]);
            }
        }
    }

    /// Backprop with lengths already checked. `work` holds the hidden activations (layer by
    /// layer) followed by two delta buffers; nothing is allocated.
    pub(crate) fn jacobian_unchecked(
        &self,
        x: &[f64],
        work: &mut [f64],
        y: &mut [f64],
        jac: &mut [f64],
    ) {
        let sizes = &self.sizes;
        let n_layers = sizes.len() - 1;
        let n_hidden: usize = sizes[1..n_layers].iter().sum();
        let widest = sizes.iter().copied().max().unwrap_or(0);
        let (acts, deltas) = work.split_at_mut(n_hidden);
        let (delta, delta_prev) = deltas[..2 * widest].split_at_mut(widest);

        // Forward pass keeping every hidden activation.
        let (mut w_off, mut a_off) = (0, 0);
        for l in 0..n_layers {
            let (n_i, n_o) = (sizes[l], sizes[l + 1]);
            let w = &self.weights[w_off..w_off + n_i * n_o + n_o];
            w_off += n_i * n_o + n_o;
            let (done, rest) = acts.split_at_mut(a_off);
            let prev: &[f64] = if l == 0 { x } else { &done[a_off - n_i..] };
            if l + 1 == n_layers {
                dense(w, prev, y, |s| s);
            } else {
                self.dense_hidden(w, prev, &mut rest[..n_o]);
                a_off += n_o;
            }
        }

        // One backward sweep per output k: δ_L = e_k, ∂y_k/∂W_l = δ_{l+1} a_lᵀ,
        // ∂y_k/∂b_l = δ_{l+1}, δ_l = (W_lᵀ δ_{l+1}) ⊙ (1 − a_l²).
        let p = self.weights.len();
        let n_out = sizes[n_layers];
        for (k, jac_row) in jac.chunks_exact_mut(p).enumerate() {
            delta[..n_out].iter_mut().for_each(|d| *d = 0.0);
            delta[k] = 1.0;
            let (mut w_off, mut a_end) = (p, n_hidden);
            for l in (0..n_layers).rev() {
                let (n_i, n_o) = (sizes[l], sizes[l + 1]);
                w_off -= n_i * n_o + n_o;
                let a: &[f64] = if l == 0 { x } else { &acts[a_end - n_i..a_end] };
                let (gw, gb) = jac_row[w_off..w_off + n_i * n_o + n_o].split_at_mut(n_i * n_o);
                for ((grow, gbi), &d) in gw.chunks_exact_mut(n_i).zip(gb).zip(&delta[..n_o]) {
                    *gbi = d;
                    for (gij, aj) in grow.iter_mut().zip(a) {
                        *gij = d * aj;
                    }
                }
                if l > 0 {
                    let w = &self.weights[w_off..w_off + n_i * n_o];
                    let dp = &mut delta_prev[..n_i];
                    dp.iter_mut().for_each(|v| *v = 0.0);
                    for (row, &d) in w.chunks_exact(n_i).zip(&delta[..n_o]) {
                        for (dpj, wij) in dp.iter_mut().zip(row) {
                            *dpj += wij * d;
                        }
                    }
                    for (dpj, aj) in dp.iter_mut().zip(a) {
                        *dpj *= 1.0 - aj * aj;
                    }
                    delta[..n_i].copy_from_slice(dp);
                    a_end -= n_i;
                }
            }
        }
    }

    /// One hidden layer; the activation is matched once per layer so each arm is a tight loop.
    #[inline]
    fn dense_hidden(&self, w: &[f64], input: &[f64], out: &mut [f64]) {
        match self.activation {
            Activation::Tanh => dense(w, input, out, f64::tanh),
            Activation::FastTanh => dense(w, input, out, super::activation::fast_tanh),
        }
    }

    fn max_hidden(&self) -> usize {
        self.sizes[1..self.sizes.len() - 1]
            .iter()
            .copied()
            .max()
            .unwrap_or(0)
    }

    fn check_len(&self, buffer: &'static str, got: usize, expected: usize) -> Result<(), NnError> {
        if got == expected {
            Ok(())
        } else {
            Err(NnError::BufferLength {
                buffer,
                expected,
                got,
            })
        }
    }
}

/// `out = φ(W·input + b)` for one layer; `w` holds W row-major followed by b.
#[inline]
fn dense(w: &[f64], input: &[f64], out: &mut [f64], phi: impl Fn(f64) -> f64) {
    let n_i = input.len();
    let (wm, b) = w.split_at(out.len() * n_i);
    for ((o, row), bias) in out.iter_mut().zip(wm.chunks_exact(n_i)).zip(b) {
        *o = phi(*bias + dot(row, input));
    }
}

/// Dot product with four independent accumulators: a single running sum is one long chain of
/// dependent additions, which (not the multiplications) bounds the speed of a small layer.
/// The summation order is fixed, so results stay bit-reproducible.
#[inline]
fn dot(a: &[f64], b: &[f64]) -> f64 {
    let (a4, a_rest) = a.split_at(a.len() / 4 * 4);
    let (b4, b_rest) = b.split_at(a4.len());
    let mut acc = [0.0; 4];
    for (ca, cb) in a4.chunks_exact(4).zip(b4.chunks_exact(4)) {
        for i in 0..4 {
            acc[i] += ca[i] * cb[i];
        }
    }
    let tail = a_rest.iter().zip(b_rest).fold(0.0, |s, (x, y)| s + x * y);
    (acc[0] + acc[1]) + (acc[2] + acc[3]) + tail
}

fn param_count(sizes: &[usize]) -> usize {
    sizes.windows(2).map(|w| w[0] * w[1] + w[1]).sum()
}

fn check_sizes(sizes: &[usize]) -> Result<(), NnError> {
    if sizes.len() < 2 || sizes.contains(&0) {
        return Err(NnError::BadArchitecture {
            sizes: sizes.to_vec(),
        });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_2_2_1_net_matches_hand_computation() {
        // W1 = [[0.5, −1], [1, 2]], b1 = [0, 0.5]; W2 = [1, −2], b2 = 0.25; x = [1, 0.5]
        // z1 = [0.5 − 0.5 + 0, 1 + 1 + 0.5] = [0, 2.5] → a1 = [0, tanh 2.5]
        // tanh 2.5 = (e⁵ − 1)/(e⁵ + 1) = 147.4131591025766 / 149.4131591025766 = 0.9866142981514303
        // y = 0 − 2·0.9866142981514303 + 0.25 = −1.7232285963028606
        let mlp = Mlp::from_weights(
            &[2, 2, 1],
            vec![0.5, -1.0, 1.0, 2.0, 0.0, 0.5, 1.0, -2.0, 0.25],
        )
        .unwrap();
        let mut scratch = vec![0.0; mlp.scratch_len()];
        let mut out = [0.0];
        mlp.forward_into(&[1.0, 0.5], &mut scratch, &mut out)
            .unwrap();
        assert!((out[0] - (-1.7232285963028606)).abs() < 1e-13, "{}", out[0]);
    }

    #[test]
    fn a_net_without_hidden_layers_is_affine() {
        // y = [1·x0 + 2·x1 + 3, −x0 + 0.5]
        let mlp = Mlp::from_weights(&[2, 2], vec![1.0, 2.0, -1.0, 0.0, 3.0, 0.5]).unwrap();
        assert_eq!(mlp.scratch_len(), 0);
        assert_eq!(mlp.forward(&[2.0, -1.0]).unwrap(), vec![3.0, -1.5]);
    }

    #[test]
    fn backprop_jacobian_matches_central_finite_differences() {
        // Two hidden layers and several outputs exercise every backprop branch.
        let mlp = Mlp::random(&[3, 4, 5, 2], Init::Xavier, 7).unwrap();
        let x = [0.3, -1.2, 0.8];
        let p = mlp.n_params();
        let mut work = vec![0.0; mlp.jacobian_work_len()];
        let mut y = [0.0; 2];
        let mut jac = vec![0.0; 2 * p];
        mlp.jacobian_into(&x, &mut work, &mut y, &mut jac).unwrap();
        assert_eq!(y.to_vec(), mlp.forward(&x).unwrap());
        let h = 1e-6;
        for i in 0..p {
            let mut w = mlp.weights().to_vec();
            w[i] += h;
            let plus = Mlp::from_weights(mlp.sizes(), w.clone())
                .unwrap()
                .forward(&x)
                .unwrap();
            w[i] -= 2.0 * h;
            let minus = Mlp::from_weights(mlp.sizes(), w)
                .unwrap()
                .forward(&x)
                .unwrap();
            for k in 0..2 {
                let fd = (plus[k] - minus[k]) / (2.0 * h);
                let an = jac[k * p + i];
                // Central differences: truncation ~h² and round-off ~1e-16/h ≈ 1e-10 absolute.
                let tol = 1e-6 * an.abs().max(1e-2);
                assert!(
                    (fd - an).abs() <= tol,
                    "param {i} output {k}: fd {fd} vs {an}"
                );
            }
        }
    }

    #[test]
    fn random_init_is_reproducible_per_seed_and_differs_between_seeds() {
        let a = Mlp::random(&[2, 6, 3], Init::NguyenWidrow, 1).unwrap();
        let b = Mlp::random(&[2, 6, 3], Init::NguyenWidrow, 1).unwrap();
        let c = Mlp::random(&[2, 6, 3], Init::NguyenWidrow, 2).unwrap();
        assert_eq!(a.weights(), b.weights());
        assert_ne!(a.weights(), c.weights());
        assert!(a.weights().iter().any(|w| *w != 0.0));
    }

    #[test]
    fn wrong_buffer_lengths_and_bad_json_are_errors() {
        let mlp = Mlp::zeros(&[2, 3, 1]).unwrap();
        let mut s = vec![0.0; mlp.scratch_len()];
        let mut out = [0.0];
        assert!(mlp.forward_into(&[1.0], &mut s, &mut out).is_err());
        assert!(mlp
            .forward_into(&[1.0, 2.0], &mut [0.0; 1], &mut out)
            .is_err());
        assert!(mlp
            .forward_into(&[1.0, 2.0], &mut s, &mut [0.0; 2])
            .is_err());
        assert!(Mlp::zeros(&[2]).is_err());
        assert!(Mlp::zeros(&[2, 0, 1]).is_err());
        assert!(serde_json::from_str::<Mlp>(r#"{"sizes":[1,1],"weights":[1.0]}"#).is_err());
        assert!(serde_json::from_str::<Mlp>(r#"{"sizes":[1,1],"weights":[1.0,2.0]}"#).is_ok());
    }
}
