//! The readings stage of the compiled model: the filters over the observed inputs, the networks'
//! temperature inputs, and per part what depends on them only (module doc of `compiled`).
//!
//! Every sum here runs in the library's order (`predictor::hybrid`, `part`, `fastnet`), so the
//! values cached for the queries are bit-identical to the library's. Units: the parts' (µm,
//! µrad) with temperature inputs in °C (readings), K (history features) and dimensionless heat
//! inputs (speed and feed features).

use crate::history::{FeedHistory, ReadingHistory, SpeedHistory};
use crate::predictor::FilterState;

/// The filters, the held readings and the buffers the networks' temperature inputs are
/// assembled in (all sized at build).
#[derive(Debug, Clone)]
pub(super) struct Inputs {
    history: ReadingHistory,
    spindle_history: ReadingHistory,
    speed: SpeedHistory,
    feed: FeedHistory,
    /// The readings last observed, °C (NaN before the first).
    readings: Box<[f64]>,
    /// Whether readings were observed since the build (or the predictor's state it started
    /// from held some).
    observed: bool,
    /// Readings and shared history features: the prefix of `all` every part sees.
    n_history: usize,
    /// Inputs of the axis parts (without own-axis feeds) and of the squareness.
    n_shared: usize,
    /// Each axis part sees its own axis's feed features only.
    own_feed: bool,
    /// Feed features of X, Y, Z.
    feeds: Box<[f64]>,
    /// The spindle part's inputs; `all[..n_shared]` those of the other parts.
    all: Box<[f64]>,
    /// With `own_feed`: one axis part's inputs.
    axis: Box<[f64]>,
}

impl Inputs {
    /// The buffers for the filters of `state`; `own_feed` as the model file says.
    pub fn new(state: FilterState, own_feed_in_file: bool) -> Self {
        let FilterState {
            history,
            spindle_history,
            speed,
            feed,
            readings,
        } = state;
        let n_history = history.len();
        let own_feed = own_feed_in_file && !feed.is_empty();
        let n_feed_axis = feed.len() / 3;
        let n_shared = if own_feed {
            n_history
        } else {
            n_history + feed.len()
        };
        let n_all = n_shared + spindle_history.n_history() + speed.len();
        Self {
            n_history,
            n_shared,
            own_feed,
            feeds: vec![0.0; feed.len()].into_boxed_slice(),
            all: vec![0.0; n_all].into_boxed_slice(),
            axis: vec![0.0; n_history + if own_feed { n_feed_axis } else { 0 }].into_boxed_slice(),
            observed: readings.iter().any(|t| !t.is_nan()),
            readings: readings.into_boxed_slice(),
            history,
            spindle_history,
            speed,
            feed,
        }
    }

    /// Temperature inputs of an axis part (without products), of the spindle part.
    pub fn widths(&self) -> (usize, usize) {
        let axis = if self.own_feed {
            self.axis.len()
        } else {
            self.n_shared
        };
        (axis, self.all.len())
    }

    /// Inputs of the squareness.
    pub fn n_shared(&self) -> usize {
        self.n_shared
    }

    /// As `HybridPredictor::observe_readings` (the count was checked by the caller).
    pub fn observe_readings(&mut self, time_s: f64, temps_degc: &[f64]) {
        self.readings.copy_from_slice(temps_degc);
        self.observed = true;
        self.history.observe(time_s, temps_degc);
        self.spindle_history.observe(time_s, temps_degc);
    }

    /// Whether readings were observed (the held ones are NaN before).
    pub fn has_readings(&self) -> bool {
        self.observed
    }

    /// As `HybridPredictor::observe_spindle_speed`; whether the model uses the speed.
    pub fn observe_spindle_speed(&mut self, time_s: f64, rpm: f64) -> bool {
        let used = !self.speed.is_empty();
        if used {
            self.speed.observe(time_s, rpm);
        }
        used
    }

    /// As `HybridPredictor::observe_axis_feeds`; whether the model uses the feeds.
    pub fn observe_axis_feeds(&mut self, time_s: f64, feeds_mm_per_min: [f64; 3]) -> bool {
        let used = !self.feed.is_empty();
        if used {
            self.feed.observe(time_s, feeds_mm_per_min);
        }
        used
    }

    /// Writes the features of the held readings and filters into the buffers (the first half of
    /// `HybridPredictor::update_temps`).
    pub fn assemble(&mut self) {
        let (shared, own) = self.all.split_at_mut(self.n_shared);
        let (readings, shared_feeds) = shared.split_at_mut(self.n_history);
        self.history.features_into(&self.readings, readings);
        self.feed.features_into(&mut self.feeds);
        if !self.own_feed {
            shared_feeds.copy_from_slice(&self.feeds);
        }
        let (own, speed) = own.split_at_mut(self.spindle_history.n_history());
        self.spindle_history.history_into(&self.readings, own);
        self.speed.features_into(speed);
    }

    /// The temperature inputs of axis part `k` (after [`Self::assemble`]).
    pub fn axis_inputs(&mut self, k: usize) -> &[f64] {
        if !self.own_feed {
            return &self.all[..self.n_shared];
        }
        let n = self.feeds.len() / 3;
        self.axis[..self.n_history].copy_from_slice(&self.all[..self.n_history]);
        self.axis[self.n_history..].copy_from_slice(&self.feeds[k * n..(k + 1) * n]);
        &self.axis
    }

    /// The squareness's inputs and the spindle part's.
    pub fn shared_and_all(&self) -> (&[f64], &[f64]) {
        (&self.all[..self.n_shared], &self.all)
    }
}

/// The readings stage of one part `y = c + a_p·p + A_T·T (+ p·B·T) + net(p, T)`: intercept,
/// temperature slopes, position slope and its products, first-layer temperature columns, flat.
#[derive(Debug, Clone)]
pub(super) struct TempPart {
    n_t: usize,
    n_out: usize,
    hidden: usize,
    bilinear: bool,
    /// Position slopes held: `n_out` for a part with a position input, else 0.
    n_pos_out: usize,
    /// `[intercept n_out][lin_temp n_out×n_t][lin_pos_base n_out][lin_bil n_out×n_t]`
    /// `[b1 H][w_temp H×n_t][temp_mean n_t][temp_std n_t]` (the bilinear block only when
    /// bilinear; the position entries only for a part with a position input).
    data: Box<[f64]>,
}

/// One part's lowered coefficients, in the library's layout (`part::PartRuntime`,
/// `fastnet::SplitNet`), before they are packed.
#[derive(Debug, Clone, Default)]
pub(super) struct PartCoefficients {
    pub n_t: usize,
    pub n_out: usize,
    pub intercept: Vec<f64>,
    /// Row-major `n_out × n_t`.
    pub lin_temp: Vec<f64>,
    /// Per output, the slope of the position (empty without a position input).
    pub lin_pos: Vec<f64>,
    /// Row-major `n_out × n_t` (empty unless bilinear).
    pub lin_bil: Vec<f64>,
    /// Hidden units (0: no net).
    pub hidden: usize,
    pub b1: Vec<f64>,
    /// Row-major `H × n_t`.
    pub w_temp: Vec<f64>,
    pub temp_mean: Vec<f64>,
    pub temp_std: Vec<f64>,
}

impl TempPart {
    /// Packs a part's coefficients.
    pub fn pack(c: &PartCoefficients) -> Self {
        let mut data = Vec::new();
        for block in [
            &c.intercept,
            &c.lin_temp,
            &c.lin_pos,
            &c.lin_bil,
            &c.b1,
            &c.w_temp,
            &c.temp_mean,
            &c.temp_std,
        ] {
            data.extend_from_slice(block);
        }
        Self {
            n_t: c.n_t,
            n_out: c.n_out,
            hidden: c.hidden,
            bilinear: !c.lin_bil.is_empty(),
            n_pos_out: c.lin_pos.len(),
            data: data.into_boxed_slice(),
        }
    }

    /// For the readings `temps` (`n_t` values): the intercepts with the temperature terms
    /// (`lin_const`, `n_out`), the position slopes with the products (`lin_pos`, `n_out`; none
    /// for a part without a position input) and the first layer's temperature columns
    /// (`c`, the first `hidden` values).
    pub fn set_temps(
        &self,
        temps: &[f64],
        lin_const: &mut [f64],
        lin_pos: &mut [f64],
        c: &mut [f64],
    ) {
        let (n_t, n_out, h) = (self.n_t, self.n_out, self.hidden);
        let temps = &temps[..n_t];
        let (intercept, rest) = self.data.split_at(n_out);
        let (lin_temp, rest) = rest.split_at(n_out * n_t);
        let n_pos_out = self.n_pos_out;
        let (lin_pos_base, rest) = rest.split_at(n_pos_out);
        let (lin_bil, rest) = rest.split_at(if self.bilinear { n_out * n_t } else { 0 });
        let (b1, rest) = rest.split_at(h);
        let (w_temp, rest) = rest.split_at(h * n_t);
        let (temp_mean, temp_std) = rest.split_at(if h > 0 { n_t } else { 0 });
        for (o, lc) in lin_const.iter_mut().enumerate().take(n_out) {
            let row = &lin_temp[o * n_t..(o + 1) * n_t];
            *lc = row
                .iter()
                .zip(temps)
                .fold(intercept[o], |acc, (a, t)| acc + a * t);
        }
        for (o, lp) in lin_pos.iter_mut().enumerate().take(n_pos_out) {
            *lp = if self.bilinear {
                let row = &lin_bil[o * n_t..(o + 1) * n_t];
                row.iter()
                    .zip(temps)
                    .fold(lin_pos_base[o], |acc, (b, t)| acc + b * t)
            } else {
                lin_pos_base[o]
            };
        }
        for (j, cj) in c.iter_mut().enumerate().take(h) {
            let row = &w_temp[j * n_t..(j + 1) * n_t];
            let mut s = b1[j];
            for (((w, t), m), sd) in row.iter().zip(temps).zip(temp_mean).zip(temp_std) {
                s += w * ((t - m) / sd);
            }
            *cj = s;
        }
    }
}

/// The spindle part: its readings stage and output layer (it has no position input, so its
/// outputs are computed once per set of readings).
#[derive(Debug, Clone)]
pub(super) struct SpindleStage {
    pub part: TempPart,
    /// Hidden units (0: linear only).
    pub hidden: usize,
    /// `[w2 5×H row-major][b2 5][out_std 5][out_mean 5]` (empty without a net).
    pub head: Box<[f64]>,
    /// Scratch: `c_j` then the activations.
    pub scratch: Box<[f64]>,
}

impl SpindleStage {
    /// The five outputs (δx, δy, δz µm, εx, εy µrad) for the readings `temps`, as
    /// `PartRuntime::eval` with no position (std `exp` tanh, as the library).
    pub fn outputs(&mut self, temps: &[f64]) -> [f64; 5] {
        let h = self.hidden;
        let mut lin_const = [0.0; 5];
        let (c, a) = self.scratch.split_at_mut(h);
        self.part.set_temps(temps, &mut lin_const, &mut [], c);
        let mut out = [0.0; 5];
        if h > 0 {
            for (aj, cj) in a.iter_mut().zip(c.iter()) {
                *aj = 1.0 - 2.0 / ((2.0 * cj).exp() + 1.0);
            }
            let (w2, rest) = self.head.split_at(5 * h);
            let (b2, rest) = rest.split_at(5);
            let (sd, mean) = rest.split_at(5);
            for (k, o) in out.iter_mut().enumerate() {
                let row = &w2[k * h..(k + 1) * h];
                let y = row
                    .iter()
                    .zip(a.iter())
                    .fold(b2[k], |acc, (v, a)| acc + v * a);
                *o = y * sd[k] + mean[k];
            }
        }
        for (o, s) in out.iter_mut().zip(lin_const) {
            *o += s;
        }
        out
    }
}

/// The squareness regression `T → (α_yz, α_xz, α_xy)` µrad, flat.
#[derive(Debug, Clone)]
pub(super) struct SquarenessStage {
    pub n_in: usize,
    /// `[intercept 3][slopes 3×n_in]`.
    pub data: Box<[f64]>,
}

impl SquarenessStage {
    /// α_yz, α_xz, α_xy in µrad for the inputs `x` (as `LinearModel::predict_into`).
    pub fn predict_urad(&self, x: &[f64]) -> [f64; 3] {
        let (intercept, slopes) = self.data.split_at(3);
        let mut out = [0.0; 3];
        for ((o, c), row) in out
            .iter_mut()
            .zip(intercept)
            .zip(slopes.chunks_exact(self.n_in))
        {
            *o = row.iter().zip(x).fold(*c, |acc, (a, xj)| acc + a * xj);
        }
        out
    }
}
