//! The model file: versioned JSON holding everything a predictor needs at run time.
//!
//! ```text
//! {
//!   "format": "vmc-twin-model",
//!   "version": 7,
//!   "kind": "hybrid" | "volumetric" | "linear",
//!   "sensors": [{"name": "BXH", "unit": "degC"}, …],        // model input order
//!   "geometry": {"chain": "w X Y b Z t", "tool_offset_mm": [0, 0, -150]},
//!   "model": { … },                                         // kind-specific, below
//!   "trained_on": {"machine": {"name", "realisation", "fingerprint"} | null,
//!                  "inputs": {"sensors", "sensor_degc": [[min, max], …], "spindle_rpm"}}
//! }
//! ```
//!
//! `trained_on` (version 8, optional: older files and models trained without it have none)
//! records the machine the model was calibrated on and the range of every input, see
//! [`crate::provenance`]; read it with [`trained_on`].
//!
//! `model` of a `hybrid`: `axis_nets` (3 parts X, Y, Z: `[position mm, temps °C] →
//! [dx, dy, dz µm, rx, ry, rz µrad]`), `spindle_net` (a part `temps → [dx, dy, dz µm, rx, ry
//! µrad]`), `squareness` (linear model `temps → [α_yz, α_xz, α_xy] µrad`); a part is
//! `{"linear": linear model, "net": regressor or null, "bilinear": bool}` (the net models what
//! the linear model leaves, see `part`; version 2 introduced the parts, version 1 held bare
//! regressors; `bilinear`, version 6, says the linear model also takes the position ×
//! temperature products — an older build would misread such a part, hence the new version;
//! older files read as false), and
//! `reversal_um` (`[X, Y, Z]`, µm: the mean positioning error of a negative approach minus that of
//! a positive one, learned from bidirectional laser sweeps; version 3 added it — a version 2 file
//! is still read, with zero reversal, i.e. the forward-approach model it was), and
//! `history_taus_s` (time constants, s, of the history features of the networks' inputs, see
//! `crate::history`) with `history_sensors` (indices into `sensors` of the filtered readings;
//! absent = all) — version 4 added them; older files read as empty: present readings only; an
//! older build would ignore them, hence the new version — and `spindle_history_taus_s` with
//! `spindle_history_sensors` (the same, for features only the spindle part sees, after the
//! shared ones) — version 5 added them, older files read as none — and
//! `spindle_speed_exponents` with `spindle_speed_taus_s` (the commanded spindle speed's
//! heat-input features of the spindle part, opt-in, see `crate::history::SpeedHistory`;
//! version 7, absent = not used) — and `axis_feed_taus_s` (the axes' commanded-feed filters
//! every part sees after the shared history features, see `crate::history::FeedHistory`;
//! version 8, absent = not used). Of a
//! `volumetric`: `net` (`[X, Y, Z mm, temps] → [Ex, Ey, Ez] µm`). Of a `linear`: `scaling` (`pos_centre_mm`,
//! `pos_half_range_mm`, `temp_ref_degc`) and `regression` (features → E µm). A regressor is
//! `{"input_norm": {"mean", "std"}, "output_norm": {…}, "mlp": {"sizes", "weights"}}`
//! (normalisation in physical units, weights flat as documented in `nn::mlp`); a linear model is
//! `{"n_in", "n_out", "intercept", "slopes", "ridge"}`.
//!
//! f64 values are written in shortest round-trip form and read with `serde_json`'s
//! `float_roundtrip`, so a loaded model predicts bit-identically to the saved one.
//! Loading checks `format`, `version` and `kind` first (clear messages), then the schema, then
//! that the parts fit the sensor count.
//!
//! The model file is handled as text ([`AnyPredictor::from_json_str`], `to_json_string`): this
//! crate does no file I/O, the application reads and writes the files and names them in its
//! messages.

use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};

use crate::provenance::TrainedOn;
use crate::synthesis::MachineGeometry;

use super::hybrid::{HybridParts, HybridPredictor};
use super::linear::{LinearParts, LinearPredictor};
use super::volumetric::VolumetricPredictor;
use super::{ErrorPredictor, PredictError};

pub use super::kind::ModelKind;

/// Value of the `format` field.
pub const FORMAT_NAME: &str = "vmc-twin-model";
/// The model file version this build writes (and the newest it reads).
pub const FORMAT_VERSION: u64 = 8;
/// The oldest model file version this build reads (version 2: no `reversal_um`, read as zero).
pub const OLDEST_READ_VERSION: u64 = 2;
/// The only temperature unit models use.
const TEMP_UNIT: &str = "degC";

/// One sensor entry of a model file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SensorInfo {
    /// Sensor name (as in the dataset's `<name>_degc` column and the machine's sensor set).
    pub name: String,
    /// Unit of the reading; always `"degC"`.
    pub unit: String,
}

#[derive(Serialize)]
struct FileOut<'a, B> {
    format: &'static str,
    version: u64,
    kind: ModelKind,
    sensors: Vec<SensorInfo>,
    geometry: &'a MachineGeometry,
    model: &'a B,
    #[serde(skip_serializing_if = "Option::is_none")]
    trained_on: Option<&'a TrainedOn>,
}

#[derive(Deserialize)]
struct FileIn<B> {
    sensors: Vec<SensorInfo>,
    geometry: MachineGeometry,
    model: B,
}

fn json_err(e: serde_json::Error) -> PredictError {
    PredictError::Json { msg: e.to_string() }
}

fn to_json<B: Serialize>(
    kind: ModelKind,
    sensors: &[String],
    geometry: &MachineGeometry,
    model: &B,
    trained_on: Option<&TrainedOn>,
) -> Result<String, PredictError> {
    let out = FileOut {
        format: FORMAT_NAME,
        version: FORMAT_VERSION,
        kind,
        sensors: sensors
            .iter()
            .map(|n| SensorInfo {
                name: n.clone(),
                unit: TEMP_UNIT.into(),
            })
            .collect(),
        geometry,
        model,
        trained_on,
    };
    serde_json::to_string_pretty(&out).map_err(json_err)
}

/// What a model file records of its training (its `trained_on` object; None when it has none,
/// as files before version 8).
///
/// # Errors
/// Not JSON, not a model file, another version, or a `trained_on` that does not parse.
pub fn trained_on(text: &str) -> Result<Option<TrainedOn>, PredictError> {
    read_header(text)?;
    #[derive(Deserialize)]
    struct Only {
        trained_on: Option<TrainedOn>,
    }
    let f: Only = serde_json::from_str(text).map_err(json_err)?;
    Ok(f.trained_on)
}

/// Checks `format` and `version` and returns the `kind`.
fn read_header(text: &str) -> Result<ModelKind, PredictError> {
    let v: serde_json::Value = serde_json::from_str(text).map_err(json_err)?;
    let not_a_model = |reason: String| PredictError::NotAModel { reason };
    let obj = v
        .as_object()
        .ok_or_else(|| not_a_model("the top level is not a JSON object".into()))?;
    match obj.get("format") {
        Some(serde_json::Value::String(f)) if f == FORMAT_NAME => {}
        Some(f) => {
            return Err(not_a_model(format!(
                "`format` is {f}, expected \"{FORMAT_NAME}\""
            )))
        }
        None => return Err(not_a_model("no `format` field".into())),
    }
    let version = obj
        .get("version")
        .ok_or_else(|| not_a_model("no `version` field".into()))?;
    match version.as_u64() {
        Some(v) if (OLDEST_READ_VERSION..=FORMAT_VERSION).contains(&v) => {}
        Some(found) => {
            return Err(PredictError::UnsupportedVersion {
                found,
                oldest: OLDEST_READ_VERSION,
                supported: FORMAT_VERSION,
            })
        }
        None => {
            return Err(not_a_model(format!(
                "`version` is {version}, expected an integer"
            )))
        }
    }
    let kind = obj
        .get("kind")
        .ok_or_else(|| not_a_model("no `kind` field".into()))?;
    kind.as_str().and_then(ModelKind::from_name).ok_or_else(|| {
        not_a_model(format!(
            "unknown model kind {kind} (expected \"hybrid\", \"volumetric\" or \"linear\")"
        ))
    })
}

/// Parses a file of kind `expected`: header, schema, sensor units.
fn from_json<B: DeserializeOwned>(
    text: &str,
    expected: ModelKind,
) -> Result<(Vec<String>, MachineGeometry, B), PredictError> {
    let kind = read_header(text)?;
    if kind != expected {
        return Err(PredictError::WrongKind {
            expected: expected.name().into(),
            found: kind.name().into(),
        });
    }
    let f: FileIn<B> = serde_json::from_str(text).map_err(json_err)?;
    if let Some(s) = f.sensors.iter().find(|s| s.unit != TEMP_UNIT) {
        return Err(PredictError::Inconsistent {
            reason: format!(
                "sensor `{}` has unit \"{}\"; models read temperatures in \"{TEMP_UNIT}\"",
                s.name, s.unit
            ),
        });
    }
    if f.sensors.is_empty() {
        return Err(PredictError::Inconsistent {
            reason: "the model lists no sensors".into(),
        });
    }
    Ok((
        f.sensors.into_iter().map(|s| s.name).collect(),
        f.geometry,
        f.model,
    ))
}

/// Implements the JSON methods of one predictor type.
macro_rules! json_methods {
    ($ty:ty, $kind:expr, $body:ident, $from:expr) => {
        impl $ty {
            /// The model file text (pretty JSON, format in the `file` module doc).
            ///
            /// # Errors
            /// Only if serialisation fails (it does not for finite weights).
            pub fn to_json_string(&self) -> Result<String, PredictError> {
                self.to_json_string_with(None)
            }

            /// The model file text with what the model was trained on.
            ///
            /// # Errors
            /// Only if serialisation fails (it does not for finite weights).
            pub fn to_json_string_with(
                &self,
                trained_on: Option<&TrainedOn>,
            ) -> Result<String, PredictError> {
                to_json(
                    $kind,
                    self.sensor_names(),
                    self.geometry(),
                    &self.$body(),
                    trained_on,
                )
            }

            /// Parses a model file text of this kind.
            ///
            /// # Errors
            /// Not JSON, not a model file, another version or kind, a schema error, or parts
            /// that do not fit together.
            pub fn from_json_str(text: &str) -> Result<Self, PredictError> {
                let (sensors, geometry, body) = from_json(text, $kind)?;
                $from(sensors, geometry, body)
            }
        }
    };
}

json_methods!(
    HybridPredictor,
    ModelKind::Hybrid,
    parts,
    |s, g, b: HybridParts| HybridPredictor::from_parts(s, g, b)
);
json_methods!(
    VolumetricPredictor,
    ModelKind::Volumetric,
    volumetric_body,
    |s, g, b: VolumetricBody| VolumetricPredictor::from_parts(s, g, b.net)
);
json_methods!(
    LinearPredictor,
    ModelKind::Linear,
    parts,
    |s, g, b: LinearParts| LinearPredictor::from_parts(s, g, b)
);

/// The `model` object of a volumetric file.
#[derive(Serialize, Deserialize)]
struct VolumetricBody {
    net: crate::nn::Regressor,
}

impl VolumetricPredictor {
    fn volumetric_body(&self) -> VolumetricBody {
        VolumetricBody {
            net: self.net().clone(),
        }
    }
}

/// A predictor of any kind, as loaded from a model file whose kind is not known in advance
/// (the CLI's `--model FILE`). Dispatch is a `match`, so it stays static and inlinable.
// The hybrid variant is larger (its split nets inline); there is one predictor per machine and it
// is rarely moved, so a Box would only add an indirection on the query path.
#[allow(clippy::large_enum_variant)]
#[derive(Debug, Clone)]
pub enum AnyPredictor {
    /// A hybrid model.
    Hybrid(HybridPredictor),
    /// A volumetric MLP.
    Volumetric(VolumetricPredictor),
    /// A linear regression.
    Linear(LinearPredictor),
}

impl AnyPredictor {
    /// Which kind this is.
    pub fn kind(&self) -> ModelKind {
        match self {
            AnyPredictor::Hybrid(_) => ModelKind::Hybrid,
            AnyPredictor::Volumetric(_) => ModelKind::Volumetric,
            AnyPredictor::Linear(_) => ModelKind::Linear,
        }
    }

    /// Parses a model file of any kind.
    ///
    /// # Errors
    /// Not JSON, not a model file, another version, a schema error, or inconsistent parts.
    pub fn from_json_str(text: &str) -> Result<Self, PredictError> {
        Ok(match read_header(text)? {
            ModelKind::Hybrid => AnyPredictor::Hybrid(HybridPredictor::from_json_str(text)?),
            ModelKind::Volumetric => {
                AnyPredictor::Volumetric(VolumetricPredictor::from_json_str(text)?)
            }
            ModelKind::Linear => AnyPredictor::Linear(LinearPredictor::from_json_str(text)?),
        })
    }

    /// The model file text.
    ///
    /// # Errors
    /// Only if serialisation fails.
    pub fn to_json_string(&self) -> Result<String, PredictError> {
        self.to_json_string_with(None)
    }

    /// The model file text with what the model was trained on.
    ///
    /// # Errors
    /// Only if serialisation fails.
    pub fn to_json_string_with(
        &self,
        trained_on: Option<&TrainedOn>,
    ) -> Result<String, PredictError> {
        match self {
            AnyPredictor::Hybrid(p) => p.to_json_string_with(trained_on),
            AnyPredictor::Volumetric(p) => p.to_json_string_with(trained_on),
            AnyPredictor::Linear(p) => p.to_json_string_with(trained_on),
        }
    }

    /// Rejects a machine whose sensor names or order differ from the model's.
    ///
    /// # Errors
    /// [`PredictError::SensorMismatch`] listing expected and found names.
    pub fn check_sensors(&self, machine_sensor_names: &[String]) -> Result<(), PredictError> {
        super::check_sensor_names(self.sensor_names(), machine_sensor_names)
    }

    /// Rejects a machine whose nominal geometry (chain, tool offset to 1 nm) is not the one the
    /// model was trained for.
    ///
    /// # Errors
    /// [`PredictError::GeometryMismatch`] naming both.
    pub fn check_geometry(&self, machine: &MachineGeometry) -> Result<(), PredictError> {
        let model = self.geometry();
        let same_tool = model
            .tool_offset_mm
            .iter()
            .zip(&machine.tool_offset_mm)
            .all(|(a, b)| (a - b).abs() <= 1e-6);
        if model.chain == machine.chain && same_tool {
            Ok(())
        } else {
            Err(PredictError::GeometryMismatch {
                model_chain: model.chain.to_string(),
                model_tool_mm: model.tool_offset_mm,
                machine_chain: machine.chain.to_string(),
                machine_tool_mm: machine.tool_offset_mm,
            })
        }
    }

    /// The model for `machine`: itself when the geometry is the one it was trained for; a hybrid
    /// model synthesised for the machine's tool when only the tool differs
    /// ([`HybridPredictor::with_tool_offset_mm`]; `true` in the answer says it was).
    ///
    /// # Errors
    /// Another chain, or another tool for a volumetric or linear model (fitted on the tool-tip
    /// error of the calibration's tool): [`PredictError::GeometryMismatch`].
    pub fn for_machine_geometry(
        self,
        machine: &MachineGeometry,
    ) -> Result<(Self, bool), PredictError> {
        match (self.check_geometry(machine), self) {
            (Ok(()), me) => Ok((me, false)),
            (Err(_), AnyPredictor::Hybrid(h)) if h.geometry().chain == machine.chain => Ok((
                AnyPredictor::Hybrid(h.with_tool_offset_mm(machine.tool_offset_mm)?),
                true,
            )),
            (Err(e), _) => Err(e),
        }
    }

    /// The machine geometry stored with the model.
    pub fn geometry(&self) -> &MachineGeometry {
        match self {
            AnyPredictor::Hybrid(p) => p.geometry(),
            AnyPredictor::Volumetric(p) => p.geometry(),
            AnyPredictor::Linear(p) => p.geometry(),
        }
    }
}

impl ErrorPredictor for AnyPredictor {
    fn sensor_names(&self) -> &[String] {
        match self {
            AnyPredictor::Hybrid(p) => p.sensor_names(),
            AnyPredictor::Volumetric(p) => p.sensor_names(),
            AnyPredictor::Linear(p) => p.sensor_names(),
        }
    }

    #[inline]
    fn predict_error_mm(&mut self, q_mm: [f64; 3]) -> [f64; 3] {
        match self {
            AnyPredictor::Hybrid(p) => p.predict_error_mm(q_mm),
            AnyPredictor::Volumetric(p) => p.predict_error_mm(q_mm),
            AnyPredictor::Linear(p) => p.predict_error_mm(q_mm),
        }
    }

    fn negative_approach_shift_mm(&self) -> [f64; 3] {
        match self {
            AnyPredictor::Hybrid(p) => p.negative_approach_shift_mm(),
            AnyPredictor::Volumetric(p) => p.negative_approach_shift_mm(),
            AnyPredictor::Linear(p) => p.negative_approach_shift_mm(),
        }
    }

    fn observe_readings(&mut self, time_s: f64, temps_degc: &[f64]) {
        match self {
            AnyPredictor::Hybrid(p) => p.observe_readings(time_s, temps_degc),
            AnyPredictor::Volumetric(p) => p.observe_readings(time_s, temps_degc),
            AnyPredictor::Linear(p) => p.observe_readings(time_s, temps_degc),
        }
    }

    fn observe_spindle_speed(&mut self, time_s: f64, rpm: f64) {
        if let AnyPredictor::Hybrid(p) = self {
            p.observe_spindle_speed(time_s, rpm);
        }
    }

    fn observe_axis_feeds(&mut self, time_s: f64, feeds_mm_per_min: [f64; 3]) {
        if let AnyPredictor::Hybrid(p) = self {
            p.observe_axis_feeds(time_s, feeds_mm_per_min);
        }
    }

    fn change_tool(&mut self, tool_offset_mm: [f64; 3]) -> Result<(), PredictError> {
        match self {
            AnyPredictor::Hybrid(p) => p.change_tool(tool_offset_mm),
            AnyPredictor::Volumetric(p) => p.change_tool(tool_offset_mm),
            AnyPredictor::Linear(p) => p.change_tool(tool_offset_mm),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::testdata as td;
    use super::super::{train_hybrid, train_linear, train_volumetric, Settings};
    use super::*;

    /// Quick settings: round trips need a trained model, not a good one.
    fn quick() -> Settings {
        Settings {
            hidden_candidates: vec![6],
            max_epochs: 15,
            ..Settings::default()
        }
    }

    fn all_kinds() -> Vec<AnyPredictor> {
        let ds = td::dataset(&[4.0, 7.0], 2);
        let g = td::geometry();
        vec![
            AnyPredictor::Hybrid(train_hybrid(&ds, &g, &quick()).unwrap().0),
            AnyPredictor::Volumetric(train_volumetric(&ds, &g, &quick()).unwrap().0),
            AnyPredictor::Linear(train_linear(&ds, &g, &quick()).unwrap().0),
        ]
    }

    #[test]
    fn every_kind_round_trips_through_json_bit_identically() {
        for mut model in all_kinds() {
            let text = model.to_json_string().unwrap();
            assert!(text.contains("\"format\": \"vmc-twin-model\""));
            assert!(text.contains(&format!("\"kind\": \"{}\"", model.kind())));
            assert!(text.contains("\"chain\": \"w X Y b Z t\""));
            assert!(text.contains("\"unit\": \"degC\""));
            let mut back = AnyPredictor::from_json_str(&text).unwrap();
            assert_eq!(back.kind(), model.kind());
            assert_eq!(back.sensor_names(), model.sensor_names());
            assert_eq!(back.geometry(), model.geometry());
            for (q, t, _) in td::held_out(5.0, 9).into_iter().take(50) {
                let a = td::predict_at(&mut model, q, &t);
                let b = td::predict_at(&mut back, q, &t);
                assert_eq!(a.map(f64::to_bits), b.map(f64::to_bits), "{}", model.kind());
            }
            // And the text itself is a fixed point.
            assert_eq!(back.to_json_string().unwrap(), text);
        }
    }

    #[test]
    fn a_prediction_changes_only_when_new_readings_are_observed() {
        let q = [300.0, 150.0, -200.0];
        let cool = td::temps_degc(6.0, 600.0);
        let warm = td::temps_degc(6.0, 7200.0);
        for mut model in all_kinds() {
            let kind = model.kind();
            let mut told_warm = model.clone();
            // No reading yet: nothing to predict for.
            assert!(
                model.predict_error_mm(q).iter().all(|e| e.is_nan()),
                "{kind}"
            );
            model.observe_readings(600.0, &cool);
            let at_cool = model.predict_error_mm(q);
            assert!(at_cool.iter().all(|e| e.is_finite()), "{kind}");
            // Queries alone do not move it, whatever was queried in between.
            model.predict_error_mm([10.0, 20.0, -30.0]);
            assert_eq!(model.predict_error_mm(q), at_cool, "{kind}");
            // Warmer readings through the door do, to what a model told them alone predicts.
            model.observe_readings(7200.0, &warm);
            let at_warm = model.predict_error_mm(q);
            assert!(
                (0..3).any(|k| (at_warm[k] - at_cool[k]).abs() > 1e-4),
                "{kind}: {at_cool:?} -> {at_warm:?}"
            );
            told_warm.observe_readings(7200.0, &warm);
            assert_eq!(told_warm.predict_error_mm(q), at_warm, "{kind}");
        }
    }

    #[test]
    fn a_sensor_mismatch_lists_expected_and_found() {
        let model = all_kinds().remove(2);
        let names = |v: &[&str]| v.iter().map(|s| s.to_string()).collect::<Vec<_>>();
        assert!(model.check_sensors(&names(&td::SENSORS)).is_ok());
        let err = model
            .check_sensors(&names(&["S2", "S1", "S3", "Amb"]))
            .unwrap_err();
        assert_eq!(
            err.to_string(),
            "sensor mismatch: the model expects sensors [\"S1\", \"S2\", \"S3\", \"Amb\"] (in \
             this order), the machine has [\"S2\", \"S1\", \"S3\", \"Amb\"]"
        );
        assert!(model.check_sensors(&names(&["S1", "S2", "S3"])).is_err());
    }

    #[test]
    fn bad_version_format_and_kind_give_the_documented_messages() {
        let model = all_kinds().remove(2);
        let text = model.to_json_string().unwrap();
        // A version below the oldest read and one above this build's are refused, naming the
        // range this build reads; the file this build writes carries its own version.
        let written = format!("\"version\": {FORMAT_VERSION}");
        assert!(text.contains(&written), "{text}");
        let range = format!("this build reads versions {OLDEST_READ_VERSION} to {FORMAT_VERSION}");
        for v in [OLDEST_READ_VERSION - 1, FORMAT_VERSION + 1] {
            let changed = text.replacen(&written, &format!("\"version\": {v}"), 1);
            assert_eq!(
                AnyPredictor::from_json_str(&changed)
                    .unwrap_err()
                    .to_string(),
                format!("model file version {v} is not supported ({range})")
            );
        }
        let other = text.replacen("vmc-twin-model", "something-else", 1);
        assert_eq!(
            AnyPredictor::from_json_str(&other).unwrap_err().to_string(),
            "not a vmc-twin model file: `format` is \"something-else\", expected \"vmc-twin-model\""
        );
        assert_eq!(
            HybridPredictor::from_json_str(&text)
                .unwrap_err()
                .to_string(),
            "model file holds a `linear` model, expected `hybrid`"
        );
        let unknown = text.replacen("\"kind\": \"linear\"", "\"kind\": \"quantum\"", 1);
        assert_eq!(
            AnyPredictor::from_json_str(&unknown)
                .unwrap_err()
                .to_string(),
            "not a vmc-twin model file: unknown model kind \"quantum\" (expected \"hybrid\", \
             \"volumetric\" or \"linear\")"
        );
        let kelvin = text.replacen("\"degC\"", "\"K\"", 1);
        assert_eq!(
            AnyPredictor::from_json_str(&kelvin).unwrap_err().to_string(),
            "inconsistent model file: sensor `S1` has unit \"K\"; models read temperatures in \"degC\""
        );
        assert!(AnyPredictor::from_json_str("{ not json")
            .unwrap_err()
            .to_string()
            .starts_with("model file: "));
    }

    #[test]
    fn a_net_that_does_not_fit_the_sensor_count_is_rejected_on_load() {
        let model = all_kinds().remove(0);
        let text = model.to_json_string().unwrap();
        // Drop the last sensor from the list: the nets still expect four.
        let cut = text.replacen(
            ",\n    {\n      \"name\": \"Amb\",\n      \"unit\": \"degC\"\n    }",
            "",
            1,
        );
        assert_ne!(cut, text, "the edit must apply");
        let err = AnyPredictor::from_json_str(&cut).unwrap_err().to_string();
        assert!(
            err.starts_with("inconsistent model file: linear model `axis_x` must map 7 → 6 values")
                && err.ends_with(
                    "a bilinear part takes 1 position(s), 3 sensor inputs and their 3 products"
                ),
            "{err}"
        );
    }
}
