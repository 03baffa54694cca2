//! From dataset records to training tables: sensor selection, the validation split by cycle,
//! and fitting one MLP with hidden-width selection.

use std::collections::HashMap;

use crate::dataset::{Dataset, Instrument, Record};
use crate::history::{FeedHistory, ReadingHistory, SpeedHistory};
use crate::linreg::LinearModel;
use crate::nn::{Regressor, Samples, TrainConfig};

use super::{CandidateScore, NetSummary, PredictError, Settings, SplitKind};

/// Column names of the six measurement values (µm, µrad), in `Record::values` order.
pub(crate) const VALUE_COLUMNS: [&str; 6] =
    ["dx_um", "dy_um", "dz_um", "rx_urad", "ry_urad", "rz_urad"];

/// The sensors a model uses: names in model order and their dataset columns.
#[derive(Debug, Clone)]
pub(crate) struct SensorSelection {
    /// Names in model order.
    pub names: Vec<String>,
    /// Index of each into `Record::temps_degc`.
    pub cols: Vec<usize>,
    /// Time constants of the history features (s); empty: the present readings only.
    pub taus_s: Vec<f64>,
    /// Indices (into `names`) of the sensors with history features.
    pub history_idx: Vec<usize>,
    /// Time constants of the spindle-only history features (s).
    pub spindle_taus_s: Vec<f64>,
    /// Indices (into `names`) of the sensors with spindle-only history features.
    pub spindle_idx: Vec<usize>,
    /// History features (`x − y_τ` per filter, see [`crate::history`]) of each (cycle, time)
    /// instant, computed over the cycle's readings in time order: the shared ones, then the
    /// spindle-only ones.
    history: HashMap<String, HashMap<u64, Vec<f64>>>,
    /// Heat-input exponents of the commanded spindle speed (empty: not used).
    pub speed_exponents: Vec<f64>,
    /// Time constants of the speed's heat-input filters (s).
    pub speed_taus_s: Vec<f64>,
    /// Spindle-speed features ([`SpeedHistory`]) of each (cycle, time) instant.
    speed: HashMap<String, HashMap<u64, Vec<f64>>>,
    /// Time constants of the axis-feed filters (s; empty: not used).
    pub feed_taus_s: Vec<f64>,
    /// Axis-feed features ([`FeedHistory`]) of each (cycle, time) instant.
    feed: HashMap<String, HashMap<u64, Vec<f64>>>,
    /// Whether each axis part sees only its own axis's feed features (and no other part sees
    /// any) instead of every part seeing all three axes' ([`Settings::axis_feed_own_axis`]).
    pub feed_own_axis: bool,
}

impl SensorSelection {
    /// Picks `settings.sensors` (all dataset sensors when empty) and checks every record.
    pub fn new(ds: &Dataset, settings: &Settings) -> Result<Self, PredictError> {
        for (index, r) in ds.records.iter().enumerate() {
            if r.temps_degc.len() != ds.sensor_names.len() {
                return Err(PredictError::RaggedTemperatures {
                    index,
                    expected: ds.sensor_names.len(),
                    got: r.temps_degc.len(),
                });
            }
        }
        let names = if settings.sensors.is_empty() {
            ds.sensor_names.clone()
        } else {
            settings.sensors.clone()
        };
        let missing: Vec<String> = names
            .iter()
            .filter(|n| !ds.sensor_names.contains(n))
            .cloned()
            .collect();
        if !missing.is_empty() || names.is_empty() {
            return Err(PredictError::SensorsNotInDataset {
                missing,
                asked: names,
                found: ds.sensor_names.clone(),
            });
        }
        let cols = names
            .iter()
            .filter_map(|n| ds.sensor_names.iter().position(|d| d == n))
            .collect();
        Ok(Self {
            names,
            cols,
            taus_s: Vec::new(),
            history_idx: Vec::new(),
            spindle_taus_s: Vec::new(),
            spindle_idx: Vec::new(),
            history: HashMap::new(),
            speed_exponents: Vec::new(),
            speed_taus_s: Vec::new(),
            speed: HashMap::new(),
            feed_taus_s: Vec::new(),
            feed: HashMap::new(),
            feed_own_axis: false,
        })
    }

    /// Adds history features with time constants `taus_s`: each cycle's readings (every record
    /// of the cycle, whatever its instrument, in time order) run through the filters from the
    /// cycle's first record on (steady state assumed there).
    /// `of_sensors` names the sensors that get them (empty: all). `spindle` adds, the same way,
    /// features that only the spindle part sees (time constants, sensors).
    pub fn with_history(
        mut self,
        ds: &Dataset,
        taus_s: &[f64],
        of_sensors: &[String],
        spindle: (&[f64], &[String]),
    ) -> Result<Self, PredictError> {
        check_taus("history_taus_s", taus_s)?;
        check_taus("spindle_history_taus_s", spindle.0)?;
        self.taus_s = taus_s.to_vec();
        self.spindle_taus_s = spindle.0.to_vec();
        if taus_s.is_empty() && spindle.0.is_empty() {
            return Ok(self);
        }
        self.history_idx = self.indices_of("history_sensors", of_sensors)?;
        self.spindle_idx = self.indices_of("spindle_history_sensors", spindle.1)?;
        if taus_s.is_empty() {
            self.history_idx.clear();
        }
        if spindle.0.is_empty() {
            self.spindle_idx.clear();
        }
        let n = self.cols.len();
        let mut x = vec![0.0; n];
        for (cycle, recs) in records_by_cycle(ds) {
            let mut h = ReadingHistory::of_sensors(taus_s, n, &self.history_idx);
            let mut hs = ReadingHistory::of_sensors(spindle.0, n, &self.spindle_idx);
            let at = self.history.entry(cycle.to_string()).or_default();
            for r in recs {
                let key = r.time_s.to_bits();
                if at.contains_key(&key) {
                    continue;
                }
                for (xi, &c) in x.iter_mut().zip(&self.cols) {
                    *xi = r.temps_degc[c];
                }
                h.observe(r.time_s, &x);
                hs.observe(r.time_s, &x);
                let mut f = vec![0.0; h.n_history() + hs.n_history()];
                let (shared, own) = f.split_at_mut(h.n_history());
                h.history_into(&x, shared);
                hs.history_into(&x, own);
                at.insert(key, f);
            }
        }
        Ok(self)
    }

    /// Adds the commanded spindle speed's heat-input features for the spindle part (see
    /// [`SpeedHistory`]): each cycle's `spindle_rpm` log (every record, in time order) runs
    /// through the filters from the cycle's first record on (spindle at rest before it).
    /// Nothing with no exponents; every record must carry the speed otherwise.
    pub fn with_spindle_speed(
        mut self,
        ds: &Dataset,
        exponents: &[f64],
        taus_s: &[f64],
    ) -> Result<Self, PredictError> {
        if exponents.is_empty() {
            return Ok(self);
        }
        check_taus("spindle_speed_taus_s", taus_s)?;
        if let Some(e) = crate::history::invalid_speed_exponent(exponents) {
            return Err(PredictError::BadSettings {
                field: "spindle_speed_exponents",
                reason: format!(
                    "heat-input exponents must lie in (0, {}], got {e}",
                    crate::history::MAX_SPEED_EXPONENT
                ),
            });
        }
        self.speed_exponents = exponents.to_vec();
        self.speed_taus_s = taus_s.to_vec();
        if let Some((index, r)) = ds
            .records
            .iter()
            .enumerate()
            .find(|(_, r)| r.spindle_rpm.is_none())
        {
            return Err(PredictError::MissingSpindleSpeed {
                index,
                cycle: r.cycle.clone(),
                time_s: r.time_s,
            });
        }
        for (cycle, recs) in records_by_cycle(ds) {
            let mut h = SpeedHistory::new(exponents, taus_s);
            let at = self.speed.entry(cycle.to_string()).or_default();
            for r in recs {
                let key = r.time_s.to_bits();
                if at.contains_key(&key) {
                    continue;
                }
                h.observe(r.time_s, r.spindle_rpm.unwrap_or(0.0));
                let mut f = vec![0.0; h.len()];
                h.features_into(&mut f);
                at.insert(key, f);
            }
        }
        Ok(self)
    }

    /// Adds the axes' commanded-feed features (see [`FeedHistory`]) for every part: each
    /// cycle's axis-feed log (every record, in time order) runs through the filters from the
    /// cycle's first record on (axes at rest before it). Nothing with no time constants; every
    /// record must carry the feeds otherwise.
    /// With `own_axis`, axis part k sees only axis k's features and no other part sees any.
    pub fn with_axis_feeds(
        mut self,
        ds: &Dataset,
        taus_s: &[f64],
        own_axis: bool,
    ) -> Result<Self, PredictError> {
        if taus_s.is_empty() {
            return Ok(self);
        }
        self.feed_own_axis = own_axis;
        check_taus("axis_feed_taus_s", taus_s)?;
        self.feed_taus_s = taus_s.to_vec();
        if let Some((index, r)) = ds
            .records
            .iter()
            .enumerate()
            .find(|(_, r)| r.axis_feed_mm_per_min.is_none())
        {
            return Err(PredictError::MissingAxisFeeds {
                index,
                cycle: r.cycle.clone(),
                time_s: r.time_s,
            });
        }
        for_each_feed_instant(ds, taus_s, |cycle, time_s, f| {
            self.feed
                .entry(cycle.to_string())
                .or_default()
                .insert(time_s.to_bits(), f.to_vec());
        });
        Ok(self)
    }

    /// Axis-feed features of all three axes.
    pub fn n_feed(&self) -> usize {
        FeedHistory::n_features(self.feed_taus_s.len())
    }

    /// The range (within the three axes' feed features) that the part of axis `axis` (None:
    /// the spindle, the squareness, a baseline) sees.
    fn feed_range(&self, axis: Option<usize>) -> std::ops::Range<usize> {
        let n = self.feed_taus_s.len();
        match (self.feed_own_axis, axis) {
            (false, _) => 0..self.n_feed(),
            (true, Some(k)) => k * n..(k + 1) * n,
            (true, None) => 0..0,
        }
    }

    /// Spindle-speed features of the spindle part.
    fn n_speed(&self) -> usize {
        SpeedHistory::n_features(self.speed_exponents.len(), self.speed_taus_s.len())
    }

    /// Indices into `names` of `of_sensors` (all when empty); `field` names the setting.
    fn indices_of(
        &self,
        field: &'static str,
        of_sensors: &[String],
    ) -> Result<Vec<usize>, PredictError> {
        if of_sensors.is_empty() {
            return Ok((0..self.names.len()).collect());
        }
        of_sensors
            .iter()
            .map(|s| {
                self.names
                    .iter()
                    .position(|n| n == s)
                    .ok_or_else(|| PredictError::BadSettings {
                        field,
                        reason: format!("`{s}` is not among the model's sensors {:?}", self.names),
                    })
            })
            .collect()
    }

    /// History features every part sees.
    fn n_shared_history(&self) -> usize {
        self.history_idx.len() * self.taus_s.len()
    }

    /// Model inputs of the part of axis `axis` (None: the squareness or a baseline): the
    /// readings, then the history features, then the axis-feed features it sees.
    pub fn n_inputs_of(&self, axis: Option<usize>) -> usize {
        self.cols.len() + self.n_shared_history() + self.feed_range(axis).len()
    }

    /// Model inputs of the spindle part: [`Self::n_inputs_of`] `None` (readings, shared
    /// history, axis feeds it sees), then the spindle-only history features, then the
    /// spindle-speed features.
    pub fn n_spindle_inputs(&self) -> usize {
        self.n_inputs_of(None) + self.spindle_idx.len() * self.spindle_taus_s.len() + self.n_speed()
    }

    /// Appends the selected temperatures of `r` (then its history features, if any, and the
    /// axis-feed features the part of `axis` sees) to `row`; with `spindle`, also the
    /// spindle-only history features.
    pub fn push_temps(&self, r: &Record, row: &mut Vec<f64>, spindle: bool, axis: Option<usize>) {
        row.extend(self.cols.iter().map(|&c| r.temps_degc[c]));
        let n_shared = self.n_shared_history();
        let n_own = if spindle {
            self.spindle_idx.len() * self.spindle_taus_s.len()
        } else {
            0
        };
        // Every record's instant was filled in `with_history` and `with_axis_feeds`.
        let at = |map: &HashMap<String, HashMap<u64, Vec<f64>>>| {
            map.get(r.cycle.as_str())
                .and_then(|at| at.get(&r.time_s.to_bits()))
                .cloned()
        };
        let history = if n_shared + n_own > 0 {
            at(&self.history)
        } else {
            None
        };
        let mut push = |from: usize, n: usize, f: &Option<Vec<f64>>| {
            if n > 0 {
                match f {
                    Some(f) => row.extend_from_slice(&f[from..from + n]),
                    None => row.extend(std::iter::repeat_n(0.0, n)),
                }
            }
        };
        push(0, n_shared, &history);
        let fr = self.feed_range(axis);
        let feed = if fr.is_empty() { None } else { at(&self.feed) };
        push(fr.start, fr.len(), &feed);
        push(n_shared, n_own, &history);
        let ns = self.n_speed();
        if spindle && ns > 0 {
            // Every record's instant was filled in `with_spindle_speed`.
            match self
                .speed
                .get(r.cycle.as_str())
                .and_then(|at| at.get(&r.time_s.to_bits()))
            {
                Some(f) => row.extend_from_slice(f),
                None => row.extend(std::iter::repeat_n(0.0, ns)),
            }
        }
    }
}

/// Cycle ids (first-appearance order over the whole dataset) and the validation cycles.
#[derive(Debug, Clone)]
pub(crate) struct CycleSplit {
    /// Cycle names; a record's group id is the index of its cycle here.
    pub names: Vec<String>,
    /// Group ids held out for validation.
    pub val: Vec<u64>,
}

impl CycleSplit {
    /// Chooses the validation cycles: `settings.val_cycles` if given, else every
    /// `round(1/val_fraction)`-th cycle (the last one if that picks none), none with one cycle.
    pub fn new(ds: &Dataset, settings: &Settings) -> Result<Self, PredictError> {
        let mut names: Vec<String> = Vec::new();
        for r in &ds.records {
            if !names.contains(&r.cycle) {
                names.push(r.cycle.clone());
            }
        }
        let val: Vec<u64> =
            if settings.val_cycles.is_empty() {
                let f = settings.val_fraction;
                if !(f > 0.0 && f < 1.0) {
                    return Err(PredictError::BadSettings {
                        field: "val_fraction",
                        reason: format!("must lie in (0, 1), got {f}"),
                    });
                }
                let stride = ((1.0 / f).round() as usize).max(2);
                let n = names.len();
                let mut v: Vec<u64> = (0..n)
                    .filter(|i| i % stride == stride - 1)
                    .map(|i| i as u64)
                    .collect();
                if v.is_empty() && n >= 2 {
                    v.push((n - 1) as u64);
                }
                v
            } else {
                let mut v = Vec::new();
                for c in &settings.val_cycles {
                    let id = names.iter().position(|n| n == c).ok_or_else(|| {
                        PredictError::BadSettings {
                            field: "val_cycles",
                            reason: format!(
                                "cycle \"{c}\" is not in the dataset (cycles: {names:?})"
                            ),
                        }
                    })?;
                    v.push(id as u64);
                }
                if v.len() == names.len() {
                    return Err(PredictError::BadSettings {
                        field: "val_cycles",
                        reason: "every cycle is held out: nothing is left to train on".into(),
                    });
                }
                v
            };
        Ok(Self { names, val })
    }

    /// Group id of a cycle name (it is always present: ids come from the same dataset).
    pub fn id(&self, cycle: &str) -> u64 {
        self.names.iter().position(|n| n == cycle).unwrap_or(0) as u64
    }

    /// Names of the validation cycles.
    pub fn val_names(&self) -> Vec<String> {
        self.val
            .iter()
            .map(|&i| self.names[i as usize].clone())
            .collect()
    }
}

/// Training rows of one model: samples plus the cycle id of each row.
pub(crate) struct Table {
    pub inputs: Vec<Vec<f64>>,
    pub targets: Vec<Vec<f64>>,
    pub groups: Vec<u64>,
}

impl Table {
    pub fn new() -> Self {
        Self {
            inputs: Vec::new(),
            targets: Vec::new(),
            groups: Vec::new(),
        }
    }

    /// Splits by cycle, or into contiguous blocks when one side would be empty.
    pub fn split(
        &self,
        split: &CycleSplit,
        net: &'static str,
    ) -> Result<(Samples, Samples, SplitKind), PredictError> {
        let err = |e| PredictError::Net {
            net,
            cause: crate::nn::NnError::Data(e),
        };
        let all = Samples::from_rows(&self.inputs, &self.targets).map_err(err)?;
        // `split_by_groups` refuses a split with an empty side; that is the fallback case.
        if let Ok((tr, va)) = all.split_by_groups(&self.groups, &split.val) {
            if !tr.is_empty() && !va.is_empty() {
                return Ok((tr, va, SplitKind::ByCycle));
            }
        }
        let (tr, va) = all.split_blocks(5, 5).map_err(err)?;
        Ok((tr, va, SplitKind::Blocks))
    }
}

/// The values `cols` of a record, failing on an empty cell.
pub(crate) fn required_values(
    r: &Record,
    cols: &[usize],
    instrument: Instrument,
) -> Result<Vec<f64>, PredictError> {
    cols.iter()
        .map(|&c| {
            let v = r.values[c];
            if v.is_nan() {
                Err(PredictError::MissingValue {
                    instrument: instrument.name(),
                    cycle: r.cycle.clone(),
                    time_s: r.time_s,
                    column: VALUE_COLUMNS[c],
                })
            } else {
                Ok(v)
            }
        })
        .collect()
}

/// Records of `instrument`, failing when there are fewer than `needed`.
pub(crate) fn records_of<'a>(
    ds: &'a Dataset,
    instrument: Instrument,
    needed_for: &'static str,
    needed: usize,
) -> Result<Vec<&'a Record>, PredictError> {
    let recs: Vec<&Record> = ds.of(instrument).collect();
    if recs.is_empty() {
        return Err(PredictError::MissingInstrument {
            instrument: instrument.name(),
            needed_for,
        });
    }
    if recs.len() < needed {
        return Err(PredictError::TooFewRecords {
            instrument: instrument.name(),
            found: recs.len(),
            needed,
        });
    }
    Ok(recs)
}

/// SplitMix64 step: decorrelates the per-network seeds derived from one master seed.
pub(crate) fn mix_seed(seed: u64, net_index: u64) -> u64 {
    let mut z = seed ^ net_index.wrapping_mul(0x9E37_79B9_7F4A_7C15);
    z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// Runs each cycle's axis-feed log (every record, in time order; records at the same instant
/// once) through the feed filters `taus_s` from the cycle's first record on (axes at rest
/// before it) and gives `f` the cycle, the instant and the features there. A record without
/// feeds counts as axes at rest.
pub(super) fn for_each_feed_instant(
    ds: &Dataset,
    taus_s: &[f64],
    mut f: impl FnMut(&str, f64, &[f64]),
) {
    let mut features = vec![0.0; FeedHistory::n_features(taus_s.len())];
    for (cycle, recs) in records_by_cycle(ds) {
        let mut h = FeedHistory::new(taus_s);
        let mut last: Option<f64> = None;
        for r in recs {
            if last == Some(r.time_s) {
                continue;
            }
            last = Some(r.time_s);
            h.observe(r.time_s, r.axis_feed_mm_per_min.unwrap_or([0.0; 3]));
            h.features_into(&mut features);
            f(cycle, r.time_s, &features);
        }
    }
}

/// The records of each cycle (in order of first appearance), each cycle's in time order.
pub(super) fn records_by_cycle(ds: &Dataset) -> Vec<(&str, Vec<&Record>)> {
    let mut by_cycle: Vec<(&str, Vec<&Record>)> = Vec::new();
    for r in &ds.records {
        match by_cycle.iter_mut().find(|(c, _)| *c == r.cycle) {
            Some((_, v)) => v.push(r),
            None => by_cycle.push((&r.cycle, vec![r])),
        }
    }
    for (_, recs) in &mut by_cycle {
        recs.sort_by(|a, b| a.time_s.total_cmp(&b.time_s));
    }
    by_cycle
}

/// Refuses time constants that are not finite and > 0 (`field` names the setting).
fn check_taus(field: &'static str, taus_s: &[f64]) -> Result<(), PredictError> {
    match crate::history::invalid_tau(taus_s) {
        Some(t) => Err(PredictError::BadSettings {
            field,
            reason: format!("time constants must be > 0 s, got {t}"),
        }),
        None => Ok(()),
    }
}

/// Per-output RMSE of `predict` over `data` (output units); empty for an empty set.
pub(crate) fn rmse_per_output(
    data: &Samples,
    mut predict: impl FnMut(&[f64], &mut [f64]),
) -> Vec<f64> {
    if data.is_empty() {
        return Vec::new();
    }
    let mut ss = vec![0.0; data.n_out()];
    let mut out = vec![0.0; data.n_out()];
    for i in 0..data.len() {
        predict(data.input(i), &mut out);
        for ((s, o), t) in ss.iter_mut().zip(&out).zip(data.target(i)) {
            *s += (o - t) * (o - t);
        }
    }
    ss.iter().map(|s| (s / data.len() as f64).sqrt()).collect()
}

/// Fits one-hidden-layer MLPs of every candidate width and keeps the best on validation.
pub(crate) fn fit_mlp(
    net: &'static str,
    outputs: &[&str],
    table: &Table,
    split: &CycleSplit,
    settings: &Settings,
    net_index: u64,
) -> Result<(Regressor, NetSummary), PredictError> {
    if settings.hidden_candidates.is_empty() || settings.hidden_candidates.contains(&0) {
        return Err(PredictError::BadSettings {
            field: "hidden_candidates",
            reason: format!(
                "need at least one width ≥ 1, got {:?}",
                settings.hidden_candidates
            ),
        });
    }
    let (tr, va, kind) = table.split(split, net)?;
    let config = TrainConfig {
        seed: mix_seed(settings.seed, net_index),
        restarts: settings.restarts,
        max_epochs: settings.max_epochs,
        patience: settings.patience,
        ..TrainConfig::default()
    };
    let mut best = None;
    let mut candidates = Vec::new();
    for &h in &settings.hidden_candidates {
        let (reg, report) = Regressor::fit(&tr, Some(&va), &[h], &config)
            .map_err(|cause| PredictError::Net { net, cause })?;
        let score = report.val_rmse[report.best_epoch];
        candidates.push(CandidateScore {
            hidden_units: h,
            val_rmse_norm: score,
        });
        if best.as_ref().is_none_or(|(_, _, s, _)| score < *s) {
            best = Some((reg, report, score, h));
        }
    }
    let (reg, report, _, h) = best.ok_or(PredictError::BadSettings {
        field: "hidden_candidates",
        reason: "no width was tried".into(),
    })?;
    let mut scratch = vec![0.0; reg.scratch_len()];
    let mut predict = |x: &[f64], o: &mut [f64]| {
        // Widths match by construction; an error here would leave `o` at its last value.
        let _ = reg.predict_into(x, &mut scratch, o);
    };
    let summary = NetSummary {
        name: net.into(),
        outputs: outputs.iter().map(|s| s.to_string()).collect(),
        hidden_units: Some(h),
        n_train: tr.len(),
        n_val: va.len(),
        split: kind,
        train_rmse: rmse_per_output(&tr, &mut predict),
        val_rmse: rmse_per_output(&va, &mut predict),
        epochs: Some(report.epochs),
        stop_reason: Some(report.stop_reason),
        candidates,
        linear_val_rmse: Vec::new(),
    };
    Ok((reg, summary))
}

/// Fits a linear model on the training part and reports both parts.
pub(crate) fn fit_linear(
    model: &'static str,
    outputs: &[&str],
    table: &Table,
    split: &CycleSplit,
    ridge: f64,
) -> Result<(LinearModel, NetSummary), PredictError> {
    let (tr, va, kind) = table.split(split, model)?;
    let lin =
        LinearModel::fit(&tr, ridge).map_err(|cause| PredictError::Linear { model, cause })?;
    let mut predict = |x: &[f64], o: &mut [f64]| {
        let _ = lin.predict_into(x, o);
    };
    let summary = NetSummary {
        name: model.into(),
        outputs: outputs.iter().map(|s| s.to_string()).collect(),
        hidden_units: None,
        n_train: tr.len(),
        n_val: va.len(),
        split: kind,
        train_rmse: rmse_per_output(&tr, &mut predict),
        val_rmse: rmse_per_output(&va, &mut predict),
        epochs: None,
        stop_reason: None,
        candidates: Vec::new(),
        linear_val_rmse: Vec::new(),
    };
    Ok((lin, summary))
}

#[cfg(test)]
mod tests {
    use super::super::testdata as td;
    use super::*;

    fn table_for(ds: &Dataset, split: &CycleSplit) -> Table {
        let mut t = Table::new();
        for r in ds.of(Instrument::Spindle) {
            // Input: the cycle id itself, so the split can be checked row by row.
            t.inputs.push(vec![split.id(&r.cycle) as f64]);
            t.targets.push(vec![r.time_s]);
            t.groups.push(split.id(&r.cycle));
        }
        t
    }

    #[test]
    fn validation_takes_whole_cycles_and_nothing_else() {
        let ds = td::dataset(&[4.0, 7.0, 5.5, 3.0, 6.0, 5.0, 4.5, 3.5], 1);
        let split = CycleSplit::new(&ds, &Settings::default()).unwrap();
        // Every 4th cycle in file order: cycle3 and cycle7.
        assert_eq!(split.val_names(), vec!["cycle3", "cycle7"]);
        let (tr, va, kind) = table_for(&ds, &split).split(&split, "t").unwrap();
        assert_eq!(kind, SplitKind::ByCycle);
        assert_eq!(va.len(), 2 * 13);
        assert!((0..va.len()).all(|i| [3.0, 7.0].contains(&va.input(i)[0])));
        assert!((0..tr.len()).all(|i| ![3.0, 7.0].contains(&tr.input(i)[0])));
    }

    #[test]
    fn explicit_validation_cycles_are_checked() {
        let ds = td::dataset(&[4.0, 7.0], 1);
        let s = Settings {
            val_cycles: vec!["cycle0".into()],
            ..Settings::default()
        };
        assert_eq!(CycleSplit::new(&ds, &s).unwrap().val, vec![0]);
        let s = Settings {
            val_cycles: vec!["warmup".into()],
            ..Settings::default()
        };
        let err = CycleSplit::new(&ds, &s).unwrap_err().to_string();
        assert_eq!(
            err,
            "invalid setting `val_cycles`: cycle \"warmup\" is not in the dataset (cycles: \
             [\"cycle0\", \"cycle1\"])"
        );
        let s = Settings {
            val_cycles: vec!["cycle0".into(), "cycle1".into()],
            ..Settings::default()
        };
        assert!(CycleSplit::new(&ds, &s).is_err());
    }

    #[test]
    fn a_single_cycle_falls_back_to_contiguous_blocks() {
        let ds = td::dataset(&[4.0], 1);
        let split = CycleSplit::new(&ds, &Settings::default()).unwrap();
        assert!(split.val.is_empty());
        let (tr, va, kind) = table_for(&ds, &split).split(&split, "t").unwrap();
        assert_eq!(kind, SplitKind::Blocks);
        // The last fifth in time order (13 rounds → rows 11 and 12 at 13 200 s and 14 400 s).
        let times: Vec<f64> = (0..va.len()).map(|i| va.target(i)[0]).collect();
        assert_eq!(times, vec![13200.0, 14400.0]);
        assert_eq!(tr.len(), 11);
    }

    #[test]
    fn derived_seeds_differ_per_network_and_per_seed() {
        // No two (seed, network) pairs of a realistic range share a derived seed.
        let mut seen = std::collections::HashSet::new();
        for seed in 0..64u64 {
            for net in 0..16u64 {
                assert!(
                    seen.insert(mix_seed(seed, net)),
                    "collision at seed {seed}, network {net}"
                );
            }
        }
        // Neighbouring seeds give unrelated networks: about half the bits differ.
        let flipped = (mix_seed(1, 0) ^ mix_seed(2, 0)).count_ones();
        assert!((16..=48).contains(&flipped), "{flipped} bits differ");
    }
}
