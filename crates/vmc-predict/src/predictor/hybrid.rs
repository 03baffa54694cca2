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

use serde::{Deserialize, Serialize};

use crate::dataset::{Dataset, Instrument, Record};
use crate::history::{ReadingHistory, SpeedHistory};
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
}

/// Query-time state: part evaluators with cached temperature-only results, scratch.
#[derive(Debug, Clone)]
struct Runtime {
    axes: [PartRuntime<6>; 3],
    spindle: PartRuntime<5>,
    /// Spindle and squareness fields hold the values for `last_readings` and the history
    /// observed so far.
    errs: ElementaryErrors,
    /// Filters over the readings seen by [`ErrorPredictor::observe_readings`]: those every
    /// part sees, those only the spindle part sees.
    history: ReadingHistory,
    spindle_history: ReadingHistory,
    /// Heat-input filters over the commanded spindle speed (no features unless the model
    /// uses the speed).
    speed: SpeedHistory,
    /// Inputs of the axis parts and the squareness (a prefix of `inputs`).
    n_shared: usize,
    /// Temperature inputs of the networks (readings, shared history features, then the
    /// spindle-only ones) of the cached results.
    inputs: Vec<f64>,
    /// Readings of the cached results.
    last_readings: Vec<f64>,
    /// Whether the cached results must be recomputed at the next query (never computed, or
    /// readings observed since, which move the history features).
    stale: bool,
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
        let k = history.len();
        let k_spindle = k + spindle_history.n_history() + speed.len();
        for (name, part) in AXIS_NETS.iter().zip(&parts.axis_nets) {
            part.check(name, 1, k, 6)?;
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
            n_shared: k,
            inputs: vec![0.0; k_spindle],
            last_readings: vec![0.0; sensors.len()],
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
    /// baselines, fitted on the tool-tip error itself, cannot do this.
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

    /// Rejects a machine whose sensor names or order differ from the model's.
    ///
    /// # Errors
    /// [`PredictError::SensorMismatch`] listing expected and found names.
    pub fn check_sensors(&self, machine_sensor_names: &[String]) -> Result<(), PredictError> {
        super::check_sensor_names(&self.sensors, machine_sensor_names)
    }

    /// The 26 predicted elementary errors (mm, rad) at axis positions `q_mm` and readings
    /// `temps_degc` (model sensor order). Allocation-free.
    pub fn elementary_errors(&mut self, q_mm: [f64; 3], temps_degc: &[f64]) -> ElementaryErrors {
        assert_temps_len(temps_degc, self.sensors.len());
        self.update_temps(temps_degc);
        let mut v = [0.0; 6];
        for (k, net) in self.rt.axes.iter_mut().enumerate() {
            net.eval(&[q_mm[k]], &mut v);
            let a = &mut self.rt.errs.axes[k];
            a.lin_mm = [v[0] * 1e-3, v[1] * 1e-3, v[2] * 1e-3];
            a.ang_rad = [v[3] * 1e-6, v[4] * 1e-6, v[5] * 1e-6];
        }
        self.rt.errs
    }

    /// Recomputes the temperature-only parts when the readings changed (bitwise) or readings
    /// were observed since the last time (the history features moved). A query between two
    /// readings only compares the readings.
    fn update_temps(&mut self, readings: &[f64]) {
        let rt = &mut self.rt;
        if !rt.stale
            && rt
                .last_readings
                .iter()
                .zip(readings)
                .all(|(a, b)| a.to_bits() == b.to_bits())
        {
            return;
        }
        rt.last_readings.copy_from_slice(readings);
        rt.stale = false;
        let (shared, own) = rt.inputs.split_at_mut(rt.n_shared);
        rt.history.features_into(readings, shared);
        let (own, speed) = own.split_at_mut(rt.spindle_history.n_history());
        rt.spindle_history.history_into(readings, own);
        rt.speed.features_into(speed);
        let temps = &rt.inputs[..rt.n_shared];
        for net in &mut rt.axes {
            net.set_temps(temps);
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
    fn predict_error_mm(&mut self, q_mm: [f64; 3], temps_degc: &[f64]) -> [f64; 3] {
        let errs = self.elementary_errors(q_mm, temps_degc);
        let e = first_order_error_mm(&self.geometry, q_mm, &errs);
        [e.x, e.y, e.z]
    }

    fn negative_approach_shift_mm(&self) -> [f64; 3] {
        self.neg_shift_mm
    }

    fn observe_readings(&mut self, time_s: f64, temps_degc: &[f64]) {
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
        )?;
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

    let mut nets = Vec::new();
    let mut axis_nets = Vec::with_capacity(3);
    for (k, table) in axis_tables.iter().enumerate() {
        let (reg, summary) = fit_linear_plus_net(
            AXIS_NETS[k],
            &VALUE_COLUMNS,
            table,
            &split,
            settings,
            k as u64,
            usize::from(settings.axis_bilinear),
        )?;
        axis_nets.push(reg);
        nets.push(summary);
    }
    let (spindle_net, summary) = fit_linear_plus_net(
        "spindle",
        &VALUE_COLUMNS[..5],
        &spindle_table,
        &split,
        settings,
        3,
        0,
    )?;
    nets.push(summary);
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
        let mut row = Vec::with_capacity(sel.n_spindle_inputs() + 1);
        if let Some(k) = pos_axis {
            row.push(r.pos_mm[k]);
        }
        sel.push_temps(r, &mut row, spindle);
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
mod tests {
    use super::super::testdata as td;
    use super::*;

    /// The default-settings model on four synthetic cycles, trained once for all tests.
    fn trained() -> (HybridPredictor, TrainSummary) {
        static MODEL: std::sync::OnceLock<(HybridPredictor, TrainSummary)> =
            std::sync::OnceLock::new();
        MODEL
            .get_or_init(|| {
                let ds = td::dataset(&[4.0, 7.0, 5.5, 3.0], 11);
                train_hybrid(&ds, &td::geometry(), &Settings::default()).unwrap()
            })
            .clone()
    }

    /// RMS of the prediction error and of the true error (µm) on a held-out cycle, with the
    /// readings transformed by `tweak` before they reach the predictor.
    fn held_out_rms(p: &mut HybridPredictor, tweak: impl Fn(&[f64]) -> Vec<f64>) -> (f64, f64) {
        let pairs: Vec<_> = td::held_out(6.0, 5)
            .into_iter()
            .map(|(q, t, e)| (p.predict_error_mm(q, &tweak(&t)), e))
            .collect();
        td::rms_um(&pairs)
    }

    #[test]
    fn a_version_5_file_reads_as_plain_parts_and_predicts_as_written() {
        // A model trained without the products, written as version 5 did (no `bilinear`).
        let ds = td::dataset(&[4.0, 7.0, 5.5, 3.0], 11);
        let plain = Settings {
            axis_bilinear: false,
            hidden_candidates: vec![6],
            max_epochs: 20,
            ..Settings::default()
        };
        let (mut p, _) = train_hybrid(&ds, &td::geometry(), &plain).unwrap();
        let mut v: serde_json::Value = serde_json::from_str(&p.to_json_string().unwrap()).unwrap();
        v["version"] = 5.into();
        let model = v["model"].as_object_mut().unwrap();
        for part in model["axis_nets"].as_array_mut().unwrap() {
            assert_eq!(
                part.as_object_mut().unwrap().remove("bilinear"),
                Some(false.into())
            );
        }
        model["spindle_net"]
            .as_object_mut()
            .unwrap()
            .remove("bilinear");
        let mut old = HybridPredictor::from_json_str(&v.to_string()).unwrap();
        let hot = td::temps_degc(6.0, 7200.0);
        for q in [[100.0, 50.0, -80.0], [400.0, 300.0, -300.0]] {
            assert_eq!(old.predict_error_mm(q, &hot), p.predict_error_mm(q, &hot));
        }
    }

    #[test]
    fn another_tool_gives_the_model_calibrated_with_that_tool() {
        // The parts learn elementary errors, which do not depend on the tool: a model moved to
        // a 250 mm tool predicts exactly what one trained with that tool predicts, and differs
        // from the 150 mm model by the angular errors times the extra 100 mm arm.
        let ds = td::dataset(&[4.0, 7.0, 5.5], 3);
        let quick = Settings {
            hidden_candidates: vec![6],
            max_epochs: 20,
            ..Settings::default()
        };
        let (p150, _) = train_hybrid(&ds, &td::geometry(), &quick).unwrap();
        let long = MachineGeometry {
            tool_offset_mm: [0.0, 0.0, -250.0],
            ..td::geometry()
        };
        let (mut p250, _) = train_hybrid(&ds, &long, &quick).unwrap();
        let mut moved = p150.with_tool_offset_mm([0.0, 0.0, -250.0]).unwrap();
        assert_eq!(moved.geometry(), &long);
        let mut p150 = p150;
        let hot = td::temps_degc(6.0, 7200.0);
        for q in [[100.0, 50.0, -80.0], [400.0, 300.0, -300.0]] {
            let m = moved.predict_error_mm(q, &hot);
            assert_eq!(m, p250.predict_error_mm(q, &hot));
            let short = p150.predict_error_mm(q, &hot);
            assert!(
                (0..3).any(|k| (m[k] - short[k]).abs() > 1e-6),
                "{m:?} vs {short:?}"
            );
        }
        assert!(p150.with_tool_offset_mm([0.0, f64::NAN, -250.0]).is_err());
    }

    #[test]
    fn the_reversal_is_learned_from_alternating_sweeps_and_survives_the_model_file() {
        // Every other measurement round sweeps backward: the positioning reading shifts by R.
        let truth_um = [-0.5, -0.6, -0.4];
        let mut ds = td::dataset(&[4.0, 7.0, 5.5, 3.0], 11);
        for r in &mut ds.records {
            let k = match r.instrument {
                Instrument::LaserX => 0,
                Instrument::LaserY => 1,
                Instrument::LaserZ => 2,
                _ => continue,
            };
            if (r.time_s / 1200.0).round() as usize % 2 == 1 {
                r.dir = -1;
                r.values[k] += truth_um[k];
            }
        }
        let quick = Settings {
            hidden_candidates: vec![6],
            max_epochs: 20,
            ..Settings::default()
        };
        let (p, _) = train_hybrid(&ds, &td::geometry(), &quick).unwrap();
        let r = p.reversal_um();
        for k in 0..3 {
            // The laser noise is 0.1 µm per reading over ~150 backward readings per axis.
            assert!((r[k] - truth_um[k]).abs() < 0.05, "axis {k}: {r:?}");
        }
        // At the tool: X and Y move the table (E = −δ), Z the head (E = +δ); mm.
        let shift = p.negative_approach_shift_mm();
        let expected = [-r[0] * 1e-3, -r[1] * 1e-3, r[2] * 1e-3];
        for k in 0..3 {
            assert!((shift[k] - expected[k]).abs() < 1e-12, "{shift:?}");
        }
        // The model file keeps it; a version 2 file (no `reversal_um`) reads with zero.
        let text = p.to_json_string().unwrap();
        let back = HybridPredictor::from_json_str(&text).unwrap();
        assert_eq!(back.reversal_um(), r);
        let mut v: serde_json::Value = serde_json::from_str(&text).unwrap();
        v["version"] = 2.into();
        v["model"].as_object_mut().unwrap().remove("reversal_um");
        let old = HybridPredictor::from_json_str(&v.to_string()).unwrap();
        assert_eq!(old.reversal_um(), [0.0; 3]);
        assert_eq!(old.negative_approach_shift_mm(), [0.0; 3]);
        // Without backward runs the reversal is zero.
        let forward_only = td::dataset(&[4.0, 7.0, 5.5, 3.0], 11);
        let (p, _) = train_hybrid(&forward_only, &td::geometry(), &quick).unwrap();
        assert_eq!(p.reversal_um(), [0.0; 3]);
    }

    #[test]
    fn history_features_follow_the_observed_readings_and_survive_the_model_file() {
        let ds = td::dataset(&[4.0, 7.0, 5.5, 3.0], 11);
        let settings = Settings {
            hidden_candidates: vec![6],
            max_epochs: 20,
            history_taus_s: vec![1800.0],
            ..Settings::default()
        };
        let (mut p, _) = train_hybrid(&ds, &td::geometry(), &settings).unwrap();
        assert_eq!(p.parts().history_taus_s, vec![1800.0]);
        let mut back = HybridPredictor::from_json_str(&p.to_json_string().unwrap()).unwrap();
        let q = [100.0, 50.0, -80.0];
        let hot = td::temps_degc(6.0, 7200.0);
        // Never observed: the filters sit at the present readings (steady state).
        let steady = p.predict_error_mm(q, &hot);
        // After a warm-up observed from cold, the history features are non-zero.
        for k in 0..=120 {
            let t = 60.0 * f64::from(k);
            let temps = td::temps_degc(6.0, t);
            p.observe_readings(t, &temps);
            back.observe_readings(t, &temps);
        }
        let warmed = p.predict_error_mm(q, &hot);
        assert_eq!(warmed, back.predict_error_mm(q, &hot));
        assert_ne!(warmed, steady);
        // A bad time constant in a file is refused.
        let mut v: serde_json::Value = serde_json::from_str(&p.to_json_string().unwrap()).unwrap();
        v["model"]["history_taus_s"] = serde_json::json!([-5.0]);
        let err = HybridPredictor::from_json_str(&v.to_string()).unwrap_err();
        assert!(err.to_string().contains("history_taus_s"), "{err}");
        // So is one in the settings.
        let bad = Settings {
            history_taus_s: vec![0.0],
            ..settings
        };
        let err = train_hybrid(&ds, &td::geometry(), &bad).unwrap_err();
        assert!(err.to_string().contains("history_taus_s"), "{err}");
    }

    #[test]
    fn spindle_only_history_reaches_the_spindle_part_alone_and_survives_the_model_file() {
        let ds = td::dataset(&[4.0, 7.0, 5.5, 3.0], 11);
        let sensor = ds.sensor_names[1].clone();
        let settings = Settings {
            hidden_candidates: vec![6],
            max_epochs: 20,
            spindle_history_taus_s: vec![300.0],
            spindle_history_sensors: vec![sensor.clone()],
            ..Settings::default()
        };
        let (mut p, _) = train_hybrid(&ds, &td::geometry(), &settings).unwrap();
        let n = ds.sensor_names.len();
        // One more input for the spindle part only.
        assert_eq!(p.parts().spindle_net.linear.n_in(), n + 1);
        for part in &p.parts().axis_nets {
            // Position, readings, and position × readings (bilinear by default).
            assert_eq!(part.linear.n_in(), 1 + n + n);
        }
        assert_eq!(p.parts().squareness.n_in(), n);
        assert_eq!(p.parts().spindle_history_sensors, vec![1]);
        let mut back = HybridPredictor::from_json_str(&p.to_json_string().unwrap()).unwrap();
        let q = [100.0, 50.0, -80.0];
        let hot = td::temps_degc(6.0, 7200.0);
        let steady = p.elementary_errors(q, &hot);
        for k in 0..=120 {
            let t = 60.0 * f64::from(k);
            let temps = td::temps_degc(6.0, t);
            p.observe_readings(t, &temps);
            back.observe_readings(t, &temps);
        }
        let warmed = p.elementary_errors(q, &hot);
        assert_eq!(warmed, back.elementary_errors(q, &hot));
        // The history moves the spindle drift and leaves the axis parts alone.
        assert_ne!(warmed.spindle, steady.spindle);
        assert_eq!(warmed.axes, steady.axes);
        // A sensor the model lacks is named in the error.
        let bad = Settings {
            spindle_history_sensors: vec!["nope".into()],
            ..settings
        };
        let err = train_hybrid(&ds, &td::geometry(), &bad).unwrap_err();
        assert!(err.to_string().contains("spindle_history_sensors"), "{err}");
        assert!(err.to_string().contains("nope"), "{err}");
    }

    #[test]
    fn spindle_speed_features_reach_the_spindle_part_alone_and_survive_the_model_file() {
        let mut ds = td::dataset(&[4.0, 7.0, 5.5, 3.0], 11);
        let settings = Settings {
            hidden_candidates: vec![6],
            max_epochs: 20,
            ..Settings::default()
        }
        .with_spindle_speed_input();
        // Without the `spindle_rpm` column the error names the first record lacking it.
        let err = train_hybrid(&ds, &td::geometry(), &settings).unwrap_err();
        assert!(
            matches!(err, PredictError::MissingSpindleSpeed { index: 0, .. }),
            "{err}"
        );
        assert!(err.to_string().contains("spindle_rpm"), "{err}");
        // A logged speed: running in the first hour of each cycle.
        for r in &mut ds.records {
            r.spindle_rpm = Some(if r.time_s < 3600.0 { 6000.0 } else { 0.0 });
        }
        let (mut p, _) = train_hybrid(&ds, &td::geometry(), &settings).unwrap();
        let n = ds.sensor_names.len();
        // Per exponent (1, 2, 3): the present heat input and three filters.
        assert_eq!(p.parts().spindle_net.linear.n_in(), n + 3 * 4);
        for part in &p.parts().axis_nets {
            assert_eq!(part.linear.n_in(), 1 + n + n);
        }
        assert_eq!(p.parts().squareness.n_in(), n);
        let text = p.to_json_string().unwrap();
        let mut back = HybridPredictor::from_json_str(&text).unwrap();
        let q = [100.0, 50.0, -80.0];
        let hot = td::temps_degc(6.0, 7200.0);
        let rest = p.elementary_errors(q, &hot);
        for k in 0..=30 {
            let t = 60.0 * f64::from(k);
            p.observe_spindle_speed(t, 9000.0);
            back.observe_spindle_speed(t, 9000.0);
        }
        let ran = p.elementary_errors(q, &hot);
        assert_eq!(ran, back.elementary_errors(q, &hot));
        // The speed moves the spindle drift and leaves the axis parts alone.
        assert_ne!(ran.spindle, rest.spindle);
        assert_eq!(ran.axes, rest.axes);
        assert_eq!(ran.squareness, rest.squareness);
        // A model without speed features ignores the speed.
        let (mut plain, _) = train_hybrid(
            &ds,
            &td::geometry(),
            &Settings {
                hidden_candidates: vec![6],
                max_epochs: 20,
                ..Settings::default()
            },
        )
        .unwrap();
        let before = plain.elementary_errors(q, &hot);
        plain.observe_spindle_speed(0.0, 0.0);
        plain.observe_spindle_speed(600.0, 9000.0);
        assert_eq!(plain.elementary_errors(q, &hot), before);
        assert!(!plain.to_json_string().unwrap().contains("spindle_speed"));
    }

    #[test]
    fn hybrid_predicts_a_held_out_cycle_within_half_a_micrometre_rms() {
        let (mut p, summary) = trained();
        let (err, truth) = held_out_rms(&mut p, |t| t.to_vec());
        // True E is several µm RMS; the prediction must be within 0.5 µm RMS (instrument noise
        // is 0.1–0.2 µm) and remove ≥ 90 % of it.
        assert!(truth > 5.0, "truth RMS {truth} µm");
        assert!(
            err < 0.5,
            "prediction RMS error {err} µm vs truth {truth} µm\n{summary:#?}"
        );
        assert!(err < 0.1 * truth);
        assert_eq!(summary.val_cycles, vec!["cycle3".to_string()]);
        assert_eq!(summary.nets.len(), 5);
        for n in &summary.nets {
            assert_eq!(n.train_rmse.len(), n.outputs.len());
            assert_eq!(n.val_rmse.len(), n.outputs.len());
            assert!(n.n_val > 0 && n.n_train > 2 * n.n_val, "{n:?}");
        }
    }

    #[test]
    fn zeroed_or_shuffled_temperatures_degrade_the_hybrid() {
        let (mut p, _) = trained();
        let (good, _) = held_out_rms(&mut p, |t| t.to_vec());
        let (zeroed, _) = held_out_rms(&mut p, |t| vec![20.0; t.len()]);
        let (shuffled, _) = held_out_rms(&mut p, |t| vec![t[2], t[0], t[3], t[1]]);
        assert!(
            zeroed > 5.0 * good,
            "good {good} µm, ambient-only {zeroed} µm"
        );
        assert!(
            shuffled > 5.0 * good,
            "good {good} µm, shuffled {shuffled} µm"
        );
    }

    #[test]
    fn the_spindle_and_squareness_parts_follow_their_truth() {
        let (mut p, _) = trained();
        let temps = td::temps_degc(6.0, 7200.0);
        let e = p.elementary_errors([100.0, 100.0, -100.0], &temps);
        let sp = td::spindle(&temps);
        let sq = td::squareness(&temps);
        // δz_b is tens of µm here; 0.5 µm and 0.5 µrad tolerances (noise 0.2).
        assert!(
            (e.spindle.lin_mm[2] * 1e3 - sp[2]).abs() < 0.5,
            "{e:?} {sp:?}"
        );
        assert!(
            (e.squareness.xy_rad * 1e6 - sq[2]).abs() < 0.5,
            "{e:?} {sq:?}"
        );
        assert!(
            (e.squareness.yz_rad * 1e6 - sq[0]).abs() < 0.5,
            "{e:?} {sq:?}"
        );
    }

    #[test]
    fn same_seed_gives_identical_weights_and_another_seed_does_not() {
        let ds = td::dataset(&[4.0, 7.0, 5.5], 3);
        let s = Settings {
            hidden_candidates: vec![6],
            max_epochs: 20,
            ..Settings::default()
        };
        let (a, _) = train_hybrid(&ds, &td::geometry(), &s).unwrap();
        let (b, _) = train_hybrid(&ds, &td::geometry(), &s).unwrap();
        assert_eq!(a.parts(), b.parts());
        let (c, _) = train_hybrid(&ds, &td::geometry(), &Settings { seed: 1, ..s }).unwrap();
        assert_ne!(a.parts().axis_nets[0], c.parts().axis_nets[0]);
    }

    #[test]
    fn a_dataset_without_spindle_records_is_named_in_the_error() {
        let mut ds = td::dataset(&[4.0, 7.0], 1);
        ds.records.retain(|r| r.instrument != Instrument::Spindle);
        let err = train_hybrid(&ds, &td::geometry(), &Settings::default()).unwrap_err();
        assert_eq!(
            err.to_string(),
            "the dataset has no `spindle` records (needed for the spindle network)"
        );
    }

    #[test]
    fn too_few_laser_records_are_rejected() {
        let mut ds = td::dataset(&[4.0, 7.0], 1);
        let mut kept = 0;
        ds.records.retain(|r: &Record| {
            if r.instrument != Instrument::LaserY {
                return true;
            }
            kept += 1;
            kept <= 7
        });
        let err = train_hybrid(&ds, &td::geometry(), &Settings::default()).unwrap_err();
        assert_eq!(
            err.to_string(),
            "the dataset has 7 `laser_y` records, at least 20 are needed"
        );
    }

    #[test]
    fn asking_for_a_sensor_the_dataset_lacks_lists_both_sets() {
        let ds = td::dataset(&[4.0, 7.0], 1);
        let s = Settings {
            sensors: vec!["S1".into(), "XD".into()],
            ..Settings::default()
        };
        let err = train_hybrid(&ds, &td::geometry(), &s).unwrap_err();
        assert_eq!(
            err.to_string(),
            "sensor columns differ from what is asked: missing [\"XD\"]; asked for [\"S1\", \
             \"XD\"], the dataset has [\"S1\", \"S2\", \"S3\", \"Amb\"]"
        );
    }

    #[test]
    fn an_empty_laser_cell_is_reported_with_its_record() {
        let mut ds = td::dataset(&[4.0, 7.0], 1);
        if let Some(r) = ds
            .records
            .iter_mut()
            .find(|r| r.instrument == Instrument::LaserZ)
        {
            r.values[4] = f64::NAN;
        }
        let err = train_hybrid(&ds, &td::geometry(), &Settings::default()).unwrap_err();
        assert_eq!(
            err.to_string(),
            "`laser_z` record of cycle \"cycle0\" at t = 0 s has no `ry_urad` value"
        );
    }
}
