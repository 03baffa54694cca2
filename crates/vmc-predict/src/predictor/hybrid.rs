//! The hybrid predictor: elementary-error networks + first-order kinematic synthesis
//! (the study's method; model in the `predictor` module doc).
//!
//! Reversal: the axis networks model the *positive* approach. When the dataset also holds
//! backward laser runs (`dir = -1`, ISO 230-2 bidirectional sweeps), each axis's reversal `R_k`
//! (µm, a constant) is estimated first: a ridge linear model `(position, temperatures) → δ_kk` is
//! fitted on the forward records, and `R_k` = mean residual of the backward records − mean
//! residual of the forward records (both runs visit the same positions, so the position profile
//! the linear model misses cancels; the temperatures account for the machine drifting between
//! the two runs). The networks are then trained on both runs, backward `δ_kk` minus `R_k`. At
//! query time `R_k` enters as the positioning error
//! `δ_kk` of an axis that approached negatively, mapped to the tool by the same first-order
//! synthesis ([`ErrorPredictor::negative_approach_shift_mm`]). Without backward records the
//! reversal is zero and the networks see the forward records only.

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::dataset::{Dataset, Instrument, Record};
use crate::history::{FeedHistory, ReadingHistory, SpeedHistory};
use crate::linreg::LinearModel;
use crate::synthesis::{first_order_error_mm, ElementaryErrors, MachineGeometry};

use super::data::{
    fit_linear, records_of, required_values, CycleSplit, SensorSelection, Table, VALUE_COLUMNS,
};
use super::kind::{check_linear_model, ModelKind};
use super::part::{fit_linear_plus_net, LinearPlusNet, PartRuntime};
use super::{assert_temps_len, ErrorPredictor, PredictError, Settings, TrainSummary};

/// Network names of the X, Y, Z axis nets.
const AXIS_NETS: [&str; 3] = ["axis_x", "axis_y", "axis_z"];
/// Outputs of the squareness regression (the `rx, ry, rz` columns of `squareness` records).
const SQUARENESS_OUTPUTS: [&str; 3] = ["a_yz_urad", "a_xz_urad", "a_xy_urad"];
/// Squareness records needed at least (a few per cycle are usual).
const MIN_SQUARENESS_RECORDS: usize = 5;

/// The trained parts of a hybrid model, in the dataset's units (µm, µrad); what the model file
/// stores under `"model"`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub(crate) struct HybridParts {
    /// X, Y, Z: `(position along the axis mm, temperatures °C) → (dx, dy, dz µm, rx, ry, rz µrad)`.
    pub axis_nets: [LinearPlusNet; 3],
    /// `temperatures °C → (dx, dy, dz µm, rx, ry µrad)` of the spindle.
    pub spindle_net: LinearPlusNet,
    /// `temperatures °C → (α_yz, α_xz, α_xy) µrad`.
    pub squareness: LinearModel,
    /// Reversal of X, Y, Z: positioning error δ_kk of a negative approach minus that of a
    /// positive one, µm (zero in version 2 files, which have no such field).
    #[serde(default)]
    pub reversal_um: [f64; 3],
    /// Time constants of the history features, s (empty in version 2–3 files: the networks
    /// see the present readings only). The networks' temperature inputs are the readings, then
    /// per time constant the readings minus their low-pass filter (see [`crate::history`]).
    #[serde(default)]
    pub history_taus_s: Vec<f64>,
    /// Indices (model sensor order) of the sensors with history features; empty with time
    /// constants means all of them.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub history_sensors: Vec<usize>,
    /// Time constants of history features that only the spindle part sees, s (version 5; empty
    /// before). The spindle part's inputs are the shared ones, then these features.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub spindle_history_taus_s: Vec<f64>,
    /// Indices of the sensors with spindle-only history features; empty with time constants
    /// means all of them.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub spindle_history_sensors: Vec<usize>,
    /// Heat-input exponents of the commanded spindle speed (version 7, opt-in; empty: the
    /// speed is not used). The spindle part's inputs end with the [`SpeedHistory`] features.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub spindle_speed_exponents: Vec<f64>,
    /// Time constants of the speed's heat-input filters, s.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub spindle_speed_taus_s: Vec<f64>,
    /// Time constants of the axes' commanded-feed filters, s (version 8; empty: the feeds are
    /// not used). Every part's inputs then hold the [`FeedHistory`] features after the shared
    /// history features.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub axis_feed_taus_s: Vec<f64>,
    /// The axis part k sees only axis k's feed features, the spindle part and the squareness
    /// none (absent: false, every part sees all three axes').
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub axis_feed_own_axis: bool,
}

/// Query-time state: the held readings, part evaluators with cached temperature-only results,
/// scratch.
#[derive(Debug, Clone)]
struct Runtime {
    axes: [PartRuntime<6>; 3],
    spindle: PartRuntime<5>,
    /// Spindle and squareness fields hold the values for `readings` and the history observed so
    /// far (once `stale` is cleared).
    errs: ElementaryErrors,
    /// Filters over the readings seen by [`ErrorPredictor::observe_readings`]: those every
    /// part sees, those only the spindle part sees.
    history: ReadingHistory,
    spindle_history: ReadingHistory,
    /// Heat-input filters over the commanded spindle speed (no features unless the model
    /// uses the speed).
    speed: SpeedHistory,
    /// Heat-input filters over the axes' commanded feeds (no features unless the model uses
    /// them).
    feed: FeedHistory,
    /// Readings and shared history features (a prefix of `inputs`).
    n_history: usize,
    /// Whether each axis part sees only its own axis's feed features (then `inputs` holds
    /// none and `axis_inputs` the parts' own inputs).
    own_feed: bool,
    /// The feed features of the three axes (X's, then Y's, then Z's).
    feeds: Vec<f64>,
    /// With `own_feed`: axis k's inputs, the shared prefix then axis k's feed features.
    axis_inputs: [Vec<f64>; 3],
    /// Inputs of the axis parts and the squareness (a prefix of `inputs`): the readings and
    /// shared history features, then the feed features.
    n_shared: usize,
    /// Temperature inputs of the networks (readings, shared history features, then the
    /// spindle-only ones) of the cached results.
    inputs: Vec<f64>,
    /// The readings last observed, °C (model sensor order; NaN before the first).
    readings: Vec<f64>,
    /// Whether the cached results must be recomputed at the next query: set when readings or a
    /// used spindle speed are observed (they move the readings, the history features and the
    /// speed features), cleared by the recomputation.
    stale: bool,
}

/// The filters over the observed inputs and the readings last observed (NaN before the first),
/// as a [`HybridPredictor`] holds them.
#[derive(Debug, Clone)]
pub(crate) struct FilterState {
    /// The shared history features' filters.
    pub history: ReadingHistory,
    /// The spindle-only history features' filters.
    pub spindle_history: ReadingHistory,
    /// The spindle speed's heat-input filters.
    pub speed: SpeedHistory,
    /// The axes' feed filters.
    pub feed: FeedHistory,
    /// The readings last observed, °C.
    pub readings: Vec<f64>,
}

/// Hybrid predictor: 3 axis MLPs + spindle MLP (each on a linear part) + squareness regression
/// + first-order synthesis.
#[derive(Debug, Clone)]
pub struct HybridPredictor {
    sensors: Vec<String>,
    geometry: MachineGeometry,
    parts: HybridParts,
    rt: Runtime,
    /// `reversal_um` as it shows at the tool (mm per E component), see
    /// [`ErrorPredictor::negative_approach_shift_mm`].
    neg_shift_mm: [f64; 3],
}

impl HybridPredictor {
    /// Assembles a predictor, checking that every part fits `sensors`.
    pub(crate) fn from_parts(
        sensors: Vec<String>,
        geometry: MachineGeometry,
        parts: HybridParts,
    ) -> Result<Self, PredictError> {
        let history = history_of(
            &sensors,
            &parts.history_taus_s,
            &parts.history_sensors,
            ("history_taus_s", "history_sensors"),
        )?;
        let spindle_history = history_of(
            &sensors,
            &parts.spindle_history_taus_s,
            &parts.spindle_history_sensors,
            ("spindle_history_taus_s", "spindle_history_sensors"),
        )?;
        let speed = SpeedHistory::new(&parts.spindle_speed_exponents, &parts.spindle_speed_taus_s);
        if let Some(t) = crate::history::invalid_tau(&parts.spindle_speed_taus_s) {
            return Err(PredictError::Inconsistent {
                reason: format!("spindle_speed_taus_s holds an unusable time constant ({t})"),
            });
        }
        if let Some(e) = crate::history::invalid_speed_exponent(&parts.spindle_speed_exponents) {
            return Err(PredictError::Inconsistent {
                reason: format!(
                    "spindle_speed_exponents holds {e}, outside (0, {}]",
                    crate::history::MAX_SPEED_EXPONENT
                ),
            });
        }
        if let Some(t) = crate::history::invalid_tau(&parts.axis_feed_taus_s) {
            return Err(PredictError::Inconsistent {
                reason: format!("axis_feed_taus_s holds an unusable time constant ({t})"),
            });
        }
        let feed = FeedHistory::new(&parts.axis_feed_taus_s);
        let n_history = history.len();
        let own_feed = parts.axis_feed_own_axis && !feed.is_empty();
        // Inputs of the squareness (and the prefix of the spindle's), and of each axis part.
        let (k, k_axis) = if own_feed {
            (n_history, n_history + parts.axis_feed_taus_s.len())
        } else {
            (n_history + feed.len(), n_history + feed.len())
        };
        let k_spindle = k + spindle_history.n_history() + speed.len();
        for (name, part) in AXIS_NETS.iter().zip(&parts.axis_nets) {
            part.check(name, 1, k_axis, 6)?;
        }
        parts.spindle_net.check("spindle", 0, k_spindle, 5)?;
        check_linear_model("squareness", &parts.squareness, k, 3)?;
        if let Some(r) = parts.reversal_um.iter().find(|r| !r.is_finite()) {
            return Err(PredictError::Inconsistent {
                reason: format!("reversal_um holds a non-finite value ({r})"),
            });
        }
        // A positioning error δ_kk of axis k moves the tool by ±δ_kk along bed axis k (the sign
        // is the carriage's side of the chain); the other first-order terms of a pure δ_kk are
        // zero.
        let neg_shift_mm: [f64; 3] = std::array::from_fn(|k| {
            let mut e = ElementaryErrors::default();
            e.axes[k].lin_mm[k] = parts.reversal_um[k] * 1e-3;
            first_order_error_mm(&geometry, [0.0; 3], &e)[k]
        });
        let axes = [
            PartRuntime::new(&parts.axis_nets[0], 1, AXIS_NETS[0])?,
            PartRuntime::new(&parts.axis_nets[1], 1, AXIS_NETS[1])?,
            PartRuntime::new(&parts.axis_nets[2], 1, AXIS_NETS[2])?,
        ];
        let spindle = PartRuntime::new(&parts.spindle_net, 0, "spindle")?;
        let rt = Runtime {
            axes,
            spindle,
            errs: ElementaryErrors::default(),
            history,
            spindle_history,
            speed,
            feeds: vec![0.0; feed.len()],
            feed,
            n_history,
            own_feed,
            axis_inputs: std::array::from_fn(|_| vec![0.0; k_axis]),
            n_shared: k,
            inputs: vec![0.0; k_spindle],
            readings: vec![f64::NAN; sensors.len()],
            stale: true,
        };
        Ok(Self {
            sensors,
            geometry,
            parts,
            rt,
            neg_shift_mm,
        })
    }

    /// Learned reversal of X, Y, Z: positioning error of a negative approach minus that of a
    /// positive one, µm (zero when the calibration had no backward runs).
    pub fn reversal_um(&self) -> [f64; 3] {
        self.parts.reversal_um
    }

    /// The same model synthesised for another tool (tool tip relative to the spindle gauge
    /// point, mm). The parts predict elementary errors of the axes and the spindle, which do not
    /// depend on the tool; the tool enters only through the synthesis (angular errors and
    /// spindle tilts times the tool's arm), so a tool change needs no recalibration. The
    /// baselines, fitted on the tool-tip error itself, cannot do this. The new model starts
    /// with no readings observed.
    ///
    /// # Errors
    /// A non-finite offset ([`PredictError::Inconsistent`]).
    pub fn with_tool_offset_mm(&self, tool_offset_mm: [f64; 3]) -> Result<Self, PredictError> {
        if let Some(v) = tool_offset_mm.iter().find(|v| !v.is_finite()) {
            return Err(PredictError::Inconsistent {
                reason: format!("tool offset holds a non-finite value ({v})"),
            });
        }
        let geometry = MachineGeometry {
            tool_offset_mm,
            ..self.geometry
        };
        Self::from_parts(self.sensors.clone(), geometry, self.parts.clone())
    }

    /// The machine geometry used by the synthesis.
    pub fn geometry(&self) -> &MachineGeometry {
        &self.geometry
    }

    /// The trained parts (for the model file).
    pub(crate) fn parts(&self) -> &HybridParts {
        &self.parts
    }

    /// The filters and the held readings as they stand (for the compiled form, which starts
    /// from the same state).
    pub(crate) fn filter_state(&self) -> FilterState {
        FilterState {
            history: self.rt.history.clone(),
            spindle_history: self.rt.spindle_history.clone(),
            speed: self.rt.speed.clone(),
            feed: self.rt.feed.clone(),
            readings: self.rt.readings.clone(),
        }
    }

    /// Rejects a machine whose sensor names or order differ from the model's.
    ///
    /// # Errors
    /// [`PredictError::SensorMismatch`] listing expected and found names.
    pub fn check_sensors(&self, machine_sensor_names: &[String]) -> Result<(), PredictError> {
        super::check_sensor_names(&self.sensors, machine_sensor_names)
    }

    /// The 26 predicted elementary errors (mm, rad) at axis positions `q_mm` under the readings
    /// last observed ([`ErrorPredictor::observe_readings`]; NaN before the first).
    /// Allocation-free.
    pub fn elementary_errors(&mut self, q_mm: [f64; 3]) -> ElementaryErrors {
        if self.rt.stale {
            self.update_temps();
        }
        let mut v = [0.0; 6];
        for (k, net) in self.rt.axes.iter_mut().enumerate() {
            net.eval(&[q_mm[k]], &mut v);
            let a = &mut self.rt.errs.axes[k];
            a.lin_mm = [v[0] * 1e-3, v[1] * 1e-3, v[2] * 1e-3];
            a.ang_rad = [v[3] * 1e-6, v[4] * 1e-6, v[5] * 1e-6];
        }
        self.rt.errs
    }

    /// Recomputes the temperature-dependent parts for the held readings and the filters' state
    /// (history and speed features, the networks' temperature inputs, the spindle drifts and the
    /// squareness). Runs at the first query after an observation: a query between two
    /// observations reuses them.
    fn update_temps(&mut self) {
        let rt = &mut self.rt;
        rt.stale = false;
        let (shared, own) = rt.inputs.split_at_mut(rt.n_shared);
        let (readings, shared_feeds) = shared.split_at_mut(rt.n_history);
        rt.history.features_into(&rt.readings, readings);
        rt.feed.features_into(&mut rt.feeds);
        if !rt.own_feed {
            shared_feeds.copy_from_slice(&rt.feeds);
        }
        let (own, speed) = own.split_at_mut(rt.spindle_history.n_history());
        rt.spindle_history.history_into(&rt.readings, own);
        rt.speed.features_into(speed);
        let temps = &rt.inputs[..rt.n_shared];
        if rt.own_feed {
            let n = rt.feeds.len() / 3;
            for (k, (net, x)) in rt.axes.iter_mut().zip(&mut rt.axis_inputs).enumerate() {
                x[..rt.n_history].copy_from_slice(&temps[..rt.n_history]);
                x[rt.n_history..].copy_from_slice(&rt.feeds[k * n..(k + 1) * n]);
                net.set_temps(x);
            }
        } else {
            for net in &mut rt.axes {
                net.set_temps(temps);
            }
        }
        rt.spindle.set_temps(&rt.inputs);
        let mut s = [0.0; 5];
        rt.spindle.eval(&[], &mut s);
        rt.errs.spindle.lin_mm = [s[0] * 1e-3, s[1] * 1e-3, s[2] * 1e-3];
        rt.errs.spindle.tilt_rad = [s[3] * 1e-6, s[4] * 1e-6];
        let mut a = [0.0; 3];
        // Widths were checked in `from_parts`, so this cannot fail.
        if self.parts.squareness.predict_into(temps, &mut a).is_ok() {
            rt.errs.squareness.yz_rad = a[0] * 1e-6;
            rt.errs.squareness.xz_rad = a[1] * 1e-6;
            rt.errs.squareness.xy_rad = a[2] * 1e-6;
        }
    }
}

impl ErrorPredictor for HybridPredictor {
    fn sensor_names(&self) -> &[String] {
        &self.sensors
    }

    #[inline]
    fn predict_error_mm(&mut self, q_mm: [f64; 3]) -> [f64; 3] {
        let errs = self.elementary_errors(q_mm);
        let e = first_order_error_mm(&self.geometry, q_mm, &errs);
        [e.x, e.y, e.z]
    }

    fn negative_approach_shift_mm(&self) -> [f64; 3] {
        self.neg_shift_mm
    }

    fn observe_readings(&mut self, time_s: f64, temps_degc: &[f64]) {
        assert_temps_len(temps_degc, self.sensors.len());
        self.rt.readings.copy_from_slice(temps_degc);
        self.rt.history.observe(time_s, temps_degc);
        self.rt.spindle_history.observe(time_s, temps_degc);
        self.rt.stale = true;
    }

    fn observe_spindle_speed(&mut self, time_s: f64, rpm: f64) {
        if !self.rt.speed.is_empty() {
            self.rt.speed.observe(time_s, rpm);
            self.rt.stale = true;
        }
    }

    fn observe_axis_feeds(&mut self, time_s: f64, feeds_mm_per_min: [f64; 3]) {
        if !self.rt.feed.is_empty() {
            self.rt.feed.observe(time_s, feeds_mm_per_min);
            self.rt.stale = true;
        }
    }

    /// Follows any tool: only the synthesis's tool arm changes (the reversal shift does not
    /// depend on it); the filtered history is kept.
    fn change_tool(&mut self, tool_offset_mm: [f64; 3]) -> Result<(), PredictError> {
        if let Some(v) = tool_offset_mm.iter().find(|v| !v.is_finite()) {
            return Err(PredictError::Inconsistent {
                reason: format!("tool offset holds a non-finite value ({v})"),
            });
        }
        self.geometry.tool_offset_mm = tool_offset_mm;
        Ok(())
    }
}

/// Trains the hybrid predictor on the `laser_x/y/z`, `spindle` and `squareness` records.
///
/// # Errors
/// A missing instrument, too few records, an empty measurement cell, sensors not in the
/// dataset, unusable settings, or a training failure.
pub fn train_hybrid(
    ds: &Dataset,
    geometry: &MachineGeometry,
    settings: &Settings,
) -> Result<(HybridPredictor, TrainSummary), PredictError> {
    let sel = SensorSelection::new(ds, settings)?
        .with_history(
            ds,
            &settings.history_taus_s,
            &settings.history_sensors,
            (
                &settings.spindle_history_taus_s,
                &settings.spindle_history_sensors,
            ),
        )?
        .with_spindle_speed(
            ds,
            &settings.spindle_speed_exponents,
            &settings.spindle_speed_taus_s,
        )?
        .with_axis_feeds(ds, &settings.axis_feed_taus_s, settings.axis_feed_own_axis)?;
    let split = CycleSplit::new(ds, settings)?;
    // Build every table before training anything, so data errors surface at once.
    const NEEDED_FOR: [&str; 3] = [
        "the X-axis network",
        "the Y-axis network",
        "the Z-axis network",
    ];
    let mut axis_tables = Vec::with_capacity(3);
    let mut reversal_um = [0.0; 3];
    for (k, needed_for) in NEEDED_FOR.iter().enumerate() {
        let instrument = Instrument::laser(k);
        let recs = records_of(ds, instrument, needed_for, settings.min_records)?;
        let mut table = table_of(
            &recs,
            &sel,
            &split,
            Some(k),
            &[0, 1, 2, 3, 4, 5],
            instrument,
            false,
        )?;
        reversal_um[k] = estimate_reversal_um(&recs, &table, k, &split, settings)?;
        // Backward runs become samples of the positive approach.
        for (r, y) in recs.iter().zip(&mut table.targets) {
            if r.dir < 0 {
                y[k] -= reversal_um[k];
            }
        }
        axis_tables.push(table);
    }
    let recs = records_of(
        ds,
        Instrument::Spindle,
        "the spindle network",
        settings.min_records,
    )?;
    let spindle_table = table_of(
        &recs,
        &sel,
        &split,
        None,
        &[0, 1, 2, 3, 4],
        Instrument::Spindle,
        true,
    )?;
    let recs = records_of(
        ds,
        Instrument::Squareness,
        "the squareness regression",
        MIN_SQUARENESS_RECORDS,
    )?;
    let sq_table = table_of(
        &recs,
        &sel,
        &split,
        None,
        &[3, 4, 5],
        Instrument::Squareness,
        false,
    )?;

    // The three axis parts and the spindle part are independent, each seeded by its index:
    // trained side by side, they give the same bits as one after the other.
    let fitted: Vec<_> = (0..4usize)
        .into_par_iter()
        .map(|k| match axis_tables.get(k) {
            Some(table) => fit_linear_plus_net(
                AXIS_NETS[k],
                &VALUE_COLUMNS,
                table,
                &split,
                settings,
                k as u64,
                usize::from(settings.axis_bilinear),
            ),
            None => fit_linear_plus_net(
                "spindle",
                &VALUE_COLUMNS[..5],
                &spindle_table,
                &split,
                settings,
                3,
                0,
            ),
        })
        .collect();
    let mut nets = Vec::new();
    let mut parts = Vec::with_capacity(4);
    for f in fitted {
        let (reg, summary) = f?;
        parts.push(reg);
        nets.push(summary);
    }
    let spindle_net = parts.pop().expect("four parts were fitted");
    let axis_nets = parts;
    let (squareness, summary) = fit_linear(
        "squareness",
        &SQUARENESS_OUTPUTS,
        &sq_table,
        &split,
        settings.squareness_ridge,
    )?;
    nets.push(summary);

    let [ax, ay, az]: [LinearPlusNet; 3] =
        axis_nets
            .try_into()
            .map_err(|_| PredictError::Inconsistent {
                reason: "expected three axis networks".into(),
            })?;
    let parts = HybridParts {
        axis_nets: [ax, ay, az],
        spindle_net,
        squareness,
        reversal_um,
        history_taus_s: sel.taus_s.clone(),
        history_sensors: if sel.history_idx.len() == sel.names.len() {
            Vec::new()
        } else {
            sel.history_idx.clone()
        },
        spindle_history_taus_s: sel.spindle_taus_s.clone(),
        spindle_history_sensors: if sel.spindle_idx.len() == sel.names.len() {
            Vec::new()
        } else {
            sel.spindle_idx.clone()
        },
        spindle_speed_exponents: sel.speed_exponents.clone(),
        spindle_speed_taus_s: sel.speed_taus_s.clone(),
        axis_feed_taus_s: sel.feed_taus_s.clone(),
        axis_feed_own_axis: sel.feed_own_axis,
    };
    let predictor = HybridPredictor::from_parts(sel.names.clone(), *geometry, parts)?;
    let summary = TrainSummary {
        kind: ModelKind::Hybrid,
        sensors: sel.names,
        val_cycles: split.val_names(),
        nets,
    };
    Ok((predictor, summary))
}

/// Reversal of axis `k`, µm, from its laser records `recs` and their `table` (module doc): 0
/// without backward records.
fn estimate_reversal_um(
    recs: &[&Record],
    table: &Table,
    k: usize,
    split: &CycleSplit,
    settings: &Settings,
) -> Result<f64, PredictError> {
    if !recs.iter().any(|r| r.dir < 0) {
        return Ok(0.0);
    }
    let mut fwd = Table::new();
    for ((r, x), (y, g)) in recs
        .iter()
        .zip(&table.inputs)
        .zip(table.targets.iter().zip(&table.groups))
    {
        if r.dir >= 0 {
            fwd.inputs.push(x.clone());
            fwd.targets.push(vec![y[k]]);
            fwd.groups.push(*g);
        }
    }
    let (lin, _) = fit_linear(
        "reversal",
        &["positioning_um"],
        &fwd,
        split,
        settings.part_ridge,
    )?;
    // Mean residual per direction: [forward, backward] sums and counts.
    let (mut sum, mut n) = ([0.0; 2], [0usize; 2]);
    let mut out = [0.0];
    for ((r, x), y) in recs.iter().zip(&table.inputs).zip(&table.targets) {
        lin.predict_into(x, &mut out)
            .map_err(|cause| PredictError::Linear {
                model: "reversal",
                cause,
            })?;
        let d = usize::from(r.dir < 0);
        sum[d] += y[k] - out[0];
        n[d] += 1;
    }
    Ok(sum[1] / n[1] as f64 - sum[0] / n[0].max(1) as f64)
}

/// Rows `[position along axis `pos_axis` (if any), temperatures…] → values[cols]`; with
/// `spindle` the temperatures include the spindle-only history features.
fn table_of(
    recs: &[&Record],
    sel: &SensorSelection,
    split: &CycleSplit,
    pos_axis: Option<usize>,
    cols: &[usize],
    instrument: Instrument,
    spindle: bool,
) -> Result<Table, PredictError> {
    let mut table = Table::new();
    for r in recs {
        let mut row = Vec::with_capacity(sel.n_spindle_inputs() + sel.n_feed() + 1);
        if let Some(k) = pos_axis {
            row.push(r.pos_mm[k]);
        }
        sel.push_temps(r, &mut row, spindle, pos_axis);
        table.inputs.push(row);
        table.targets.push(required_values(r, cols, instrument)?);
        table.groups.push(split.id(&r.cycle));
    }
    Ok(table)
}

/// The filters of one block of history features of a model file, checked: time constants
/// finite and > 0, sensor indices within `sensors` (empty: all). `fields` name them.
fn history_of(
    sensors: &[String],
    taus_s: &[f64],
    of: &[usize],
    fields: (&str, &str),
) -> Result<ReadingHistory, PredictError> {
    if let Some(t) = crate::history::invalid_tau(taus_s) {
        return Err(PredictError::Inconsistent {
            reason: format!("{} holds {t}; time constants must be > 0 s", fields.0),
        });
    }
    if let Some(i) = of.iter().find(|&&i| i >= sensors.len()) {
        return Err(PredictError::Inconsistent {
            reason: format!(
                "{} holds sensor index {i}; the model has {} sensors",
                fields.1,
                sensors.len()
            ),
        });
    }
    let idx: Vec<usize> = if of.is_empty() {
        (0..sensors.len()).collect()
    } else {
        of.to_vec()
    };
    Ok(ReadingHistory::of_sensors(taus_s, sensors.len(), &idx))
}

#[cfg(test)]
mod tests;
