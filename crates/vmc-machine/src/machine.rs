//! Machine descriptions (`machines/*.toml`; format: docs/file-formats.md): loading and validation.
//!
//! One file describes one machine: kinematic chain and travels, tool, motion limits, thermal
//! network, temperature sensors, virtual instruments and the geometric error field. The reference
//! machine `machines/vmc-reference.toml` is embedded in the binary so the main command needs no
//! arguments. Every validation error names the offending field by its dotted path
//! (`axes.travel_max_mm[1]`), so a user can fix their file without reading code.

use std::path::Path;

use serde::{Deserialize, Serialize};
use thiserror::Error;

use crate::collision_spec::CollisionSpec;
use crate::errors::ErrorFieldSpec;
use crate::motion::MotionLimits;
use crate::sensors::SensorSpec;
use crate::thermal::ThermalSpec;
use vmc_predict::synthesis::{Chain, MachineGeometry};

/// The embedded reference machine description.
pub const REFERENCE_TOML: &str = include_str!("../../../machines/vmc-reference.toml");

/// A machine file that cannot be used.
#[derive(Debug, Error)]
pub enum MachineError {
    /// The file could not be read.
    #[error("{path}: cannot read machine file: {err}")]
    Io {
        /// The file.
        path: String,
        /// Why.
        err: std::io::Error,
    },
    /// The file is not valid TOML or does not match the schema.
    #[error("{path}: {msg}")]
    Parse {
        /// The file.
        path: String,
        /// The TOML parser's message (with line and column).
        msg: String,
    },
    /// A field has a bad value.
    #[error("{path}: field `{field}`: {msg}")]
    Invalid {
        /// The file.
        path: String,
        /// Dotted path of the field.
        field: String,
        /// What is wrong.
        msg: String,
    },
    /// A five-axis machine file (it has `[[rotary]]` axes) where a three-axis one is expected.
    #[error("{path}: a five-axis machine (it has `[[rotary]]` axes) where a three-axis machine is expected")]
    FiveAxis {
        /// The file.
        path: String,
    },
}

/// Name and kinematic structure.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MachineInfo {
    /// Short name, used in reports.
    pub name: String,
    /// Free text.
    #[serde(default)]
    pub description: String,
    /// Kinematic chain, workpiece to tool, ISO 10791-6 style (e.g. `"w X Y b Z t"`).
    pub chain: String,
}

/// Axis travels and home, machine coordinates of the tool relative to the workpiece (mm).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AxesSpec {
    /// Lower travel limit of X, Y, Z, mm.
    pub travel_min_mm: [f64; 3],
    /// Upper travel limit of X, Y, Z, mm.
    pub travel_max_mm: [f64; 3],
    /// Home (start) position, mm.
    pub home_mm: [f64; 3],
    /// Work offsets G54…G59 (machine coordinates of each program zero), mm; default all zero.
    #[serde(default)]
    pub work_offsets_mm: [[f64; 3]; 6],
}

/// The tool in the spindle.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ToolSpec {
    /// Tool tip relative to the spindle gauge point, mm (a vertical tool of length L: `[0, 0, -L]`).
    pub offset_mm: [f64; 3],
    /// Tool diameter, mm (for collision checks).
    #[serde(default = "default_tool_diameter")]
    pub diameter_mm: f64,
}

fn default_tool_diameter() -> f64 {
    10.0
}

/// Virtual instruments of the calibration campaign.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct InstrumentSpec {
    /// Interferometer linear noise σ, constant part, µm (default 0.1).
    pub laser_noise_um: f64,
    /// Interferometer linear noise σ, part proportional to travel, µm/m (default 0.5).
    pub laser_noise_um_per_m: f64,
    /// Angular noise σ, µrad (default 0.5 ≈ 0.1 arcsec).
    pub angular_noise_urad: f64,
    /// Straightness noise σ, µm (default 0.2).
    pub straightness_noise_um: f64,
    /// Spindle 5-probe test noise σ, µm (default 0.1).
    pub probe_noise_um: f64,
    /// Interferometer steps along X, Y, Z, mm (the study: 40, 30, 30).
    pub laser_step_mm: [f64; 3],
    /// Time to take one laser reading (move + settle + average), s (default 6).
    pub laser_point_s: f64,
}

impl Default for InstrumentSpec {
    fn default() -> Self {
        InstrumentSpec {
            laser_noise_um: 0.1,
            laser_noise_um_per_m: 0.5,
            angular_noise_urad: 0.5,
            straightness_noise_um: 0.2,
            probe_noise_um: 0.1,
            laser_step_mm: [40.0, 30.0, 30.0],
            laser_point_s: 6.0,
        }
    }
}

/// A whole machine description.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MachineSpec {
    /// Name and chain.
    pub machine: MachineInfo,
    /// Travels and home.
    pub axes: AxesSpec,
    /// Tool.
    pub tool: ToolSpec,
    /// Feeds, rapids, accelerations.
    pub motion: MotionLimits,
    /// Thermal network.
    pub thermal: ThermalSpec,
    /// Temperature sensors (the information a predictor gets at run time).
    pub sensors: Vec<SensorSpec>,
    /// Virtual instruments.
    #[serde(default)]
    pub instruments: InstrumentSpec,
    /// Geometric error field.
    pub errors: ErrorFieldSpec,
    /// Collision geometry (holder, spindle nose, table) for `vmc-twin check`; optional.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub collision: Option<CollisionSpec>,
}

fn invalid(path: &str, field: impl Into<String>, msg: impl Into<String>) -> MachineError {
    MachineError::Invalid {
        path: path.to_string(),
        field: field.into(),
        msg: msg.into(),
    }
}

/// The text of a machine file (3- or 5-axis), read errors named by the file.
///
/// # Errors
/// [`MachineError::Io`].
pub fn read_machine_file(path: &Path) -> Result<String, MachineError> {
    crate::read::read_text(path).map_err(|err| MachineError::Io {
        path: path.display().to_string(),
        err,
    })
}

/// A machine description parsed from TOML, its numbers checked for plausibility
/// ([`crate::plausible`]) but its sections not yet validated; `path` names it in errors.
///
/// # Errors
/// [`MachineError::Parse`] with the TOML error on one line.
pub fn parse_machine_toml<T: serde::de::DeserializeOwned>(
    text: &str,
    path: &str,
) -> Result<T, MachineError> {
    let parse_error = |e: toml::de::Error| MachineError::Parse {
        path: path.to_string(),
        msg: crate::read::one_line_toml_error(&e),
    };
    // The schema first (its errors carry the line and column), then the plausibility of every
    // number (`crate::plausible`), before any section's own checks.
    let spec = toml::from_str(text).map_err(parse_error)?;
    let table: toml::Table = toml::from_str(text).map_err(parse_error)?;
    crate::plausible::check_table(&table).map_err(|e| invalid(path, e.field, e.msg))?;
    Ok(spec)
}

impl MachineSpec {
    /// The embedded reference machine.
    pub fn reference() -> Self {
        // The embedded file is checked by a test; failing here would be a build defect.
        Self::from_toml_str(REFERENCE_TOML, "machines/vmc-reference.toml")
            .expect("embedded reference machine is valid")
    }

    /// Reads and validates a machine file.
    pub fn load(path: &Path) -> Result<Self, MachineError> {
        Self::from_toml_str(&read_machine_file(path)?, &path.display().to_string())
    }

    /// Parses and validates a machine description; `path` names it in errors.
    pub fn from_toml_str(text: &str, path: &str) -> Result<Self, MachineError> {
        let spec: MachineSpec = parse_machine_toml(text, path).map_err(|e| {
            // A five-axis file fails the three-axis schema on its own sections: say what it is.
            let five = toml::from_str::<toml::Table>(text).is_ok_and(|t| t.contains_key("rotary"));
            if five {
                MachineError::FiveAxis {
                    path: path.to_string(),
                }
            } else {
                e
            }
        })?;
        spec.validate(path)?;
        Ok(spec)
    }

    /// Checks every section; the error names the first bad field.
    pub fn validate(&self, path: &str) -> Result<(), MachineError> {
        Chain::parse(&self.machine.chain)
            .map_err(|e| invalid(path, "machine.chain", e.to_string()))?;
        let a = &self.axes;
        for i in 0..3 {
            let ax = ["X", "Y", "Z"][i];
            for (name, v) in [
                ("travel_min_mm", a.travel_min_mm[i]),
                ("travel_max_mm", a.travel_max_mm[i]),
                ("home_mm", a.home_mm[i]),
            ] {
                if !v.is_finite() {
                    return Err(invalid(
                        path,
                        format!("axes.{name}[{i}]"),
                        format!("{ax}: must be a finite number"),
                    ));
                }
            }
            let travel = a.travel_max_mm[i] - a.travel_min_mm[i];
            if travel <= 0.0 {
                return Err(invalid(
                    path,
                    format!("axes.travel_max_mm[{i}]"),
                    format!(
                        "{ax} travel must be positive: max {} mm ≤ min {} mm (travel {travel} mm)",
                        a.travel_max_mm[i], a.travel_min_mm[i]
                    ),
                ));
            }
            if a.home_mm[i] < a.travel_min_mm[i] || a.home_mm[i] > a.travel_max_mm[i] {
                return Err(invalid(
                    path,
                    format!("axes.home_mm[{i}]"),
                    format!("{ax} home {} mm is outside the travel", a.home_mm[i]),
                ));
            }
            for (k, off) in a.work_offsets_mm.iter().enumerate() {
                if !off[i].is_finite() {
                    return Err(invalid(
                        path,
                        format!("axes.work_offsets_mm[{k}][{i}]"),
                        "must be a finite number",
                    ));
                }
            }
            if !self.tool.offset_mm[i].is_finite() || self.tool.offset_mm[i].abs() > 1000.0 {
                return Err(invalid(
                    path,
                    format!("tool.offset_mm[{i}]"),
                    "must be a finite number within ±1000 mm",
                ));
            }
        }
        if !(self.tool.diameter_mm.is_finite() && self.tool.diameter_mm > 0.0) {
            return Err(invalid(path, "tool.diameter_mm", "must be > 0"));
        }
        self.motion
            .validate()
            .map_err(|e| invalid(path, "motion", e.to_string()))?;
        self.thermal
            .validate()
            .map_err(|e| invalid(path, "thermal", e.to_string()))?;
        let node_names: Vec<String> = self.thermal.nodes.iter().map(|n| n.name.clone()).collect();
        if self.sensors.is_empty() {
            return Err(invalid(path, "sensors", "at least one sensor is needed"));
        }
        for (k, s) in self.sensors.iter().enumerate() {
            s.validate(k)
                .map_err(|e| invalid(path, format!("sensors[{k}]"), e.to_string()))?;
        }
        crate::sensors::validate_sensors(&self.sensors, &node_names)
            .map_err(|e| invalid(path, "sensors", e.to_string()))?;
        self.validate_instruments(path)?;
        if let Some(c) = &self.collision {
            c.validate(self.tool.offset_mm)
                .map_err(|(field, msg)| invalid(path, field, msg))?;
        }
        self.errors
            .validate(&|n| node_names.iter().any(|m| m == n))
            .map_err(|e| match e {
                crate::errors::ErrorSpecError::Field { field, msg } => invalid(path, field, msg),
            })?;
        Ok(())
    }

    fn validate_instruments(&self, path: &str) -> Result<(), MachineError> {
        let s = &self.instruments;
        for (name, v) in [
            ("laser_noise_um", s.laser_noise_um),
            ("laser_noise_um_per_m", s.laser_noise_um_per_m),
            ("angular_noise_urad", s.angular_noise_urad),
            ("straightness_noise_um", s.straightness_noise_um),
            ("probe_noise_um", s.probe_noise_um),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                return Err(invalid(
                    path,
                    format!("instruments.{name}"),
                    format!("must be a finite number ≥ 0, got {v}"),
                ));
            }
        }
        for i in 0..3 {
            let span = self.axes.travel_max_mm[i] - self.axes.travel_min_mm[i];
            let st = s.laser_step_mm[i];
            // At least 1 mm (and ≤ the travel): at most travel/1 mm readings per sweep.
            if !(st.is_finite() && st >= 1.0 && st <= span) {
                return Err(invalid(
                    path,
                    format!("instruments.laser_step_mm[{i}]"),
                    format!("must be in [1 mm, travel = {span} mm], got {st}"),
                ));
            }
        }
        if !(s.laser_point_s.is_finite() && s.laser_point_s > 0.0) {
            return Err(invalid(path, "instruments.laser_point_s", "must be > 0"));
        }
        Ok(())
    }

    /// A fingerprint of the description without its ambient profile and tool: FNV-1a (64 bit) of its
    /// canonical JSON, in hex. Two descriptions with the same fingerprint build the same machine.
    pub fn fingerprint(&self) -> String {
        // The shop's air is not part of the machine: a model calibrated in one shop is the
        // machine's model in another (its trained ranges say whether it knows that air).
        let mut machine = self.clone();
        machine.thermal.ambient = crate::thermal::AmbientProfile::Constant { temp_degc: 0.0 };
        // Nor is the tool in the spindle: a hybrid model follows a tool change (its geometry
        // check refuses the models that cannot).
        machine.tool = ToolSpec {
            offset_mm: [0.0; 3],
            diameter_mm: 0.0,
        };
        // A MachineSpec always serialises (plain data, finite numbers checked on load).
        let text = serde_json::to_string(&machine).unwrap_or_default();
        let mut h: u64 = 0xcbf2_9ce4_8422_2325;
        for b in text.bytes() {
            h ^= u64::from(b);
            h = h.wrapping_mul(0x0100_0000_01b3);
        }
        format!("{h:016x}")
    }

    /// The machine's identity for a model: name, realisation (the seed of its random parts,
    /// when known) and fingerprint.
    pub fn identity(&self, realisation: Option<u64>) -> vmc_predict::provenance::MachineIdentity {
        vmc_predict::provenance::MachineIdentity {
            name: self.machine.name.clone(),
            realisation,
            fingerprint: self.fingerprint(),
        }
    }

    /// Nominal geometry (chain + tool offset): public knowledge a predictor may use.
    pub fn geometry(&self) -> MachineGeometry {
        // validate() has parsed the chain already.
        let chain = Chain::parse(&self.machine.chain).expect("validated chain");
        MachineGeometry {
            chain,
            tool_offset_mm: self.tool.offset_mm,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::errors::spec::ValueUnit;

    const REF_PATH: &str = "machines/vmc-reference.toml";

    fn reference() -> MachineSpec {
        MachineSpec::from_toml_str(REFERENCE_TOML, REF_PATH)
            .expect("the reference machine is valid")
    }

    /// The reference text with the first `from` after `section` replaced by `to`.
    fn reference_text_with(section: &str, from: &str, to: &str) -> String {
        let start = REFERENCE_TOML.find(section).expect("section present");
        let at = start
            + REFERENCE_TOML[start..]
                .find(from)
                .expect("text present in section");
        format!(
            "{}{}{}",
            &REFERENCE_TOML[..at],
            to,
            &REFERENCE_TOML[at + from.len()..]
        )
    }

    #[test]
    fn a_five_axis_file_is_named_as_such_not_as_a_schema_error() {
        let five = std::fs::read_to_string(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../machines/trunnion-bc.toml"
        ))
        .expect("the B/C machine file is in the repository");
        let err = MachineSpec::from_toml_str(&five, "bc.toml").unwrap_err();
        assert!(matches!(err, MachineError::FiveAxis { .. }), "{err:?}");
        assert!(
            err.to_string().starts_with("bc.toml: a five-axis machine"),
            "{err}"
        );
        // A three-axis file with a misspelt section still gets the schema's message.
        let bad = reference_text_with("[axes]", "[axes]", "[axis]");
        let err = MachineSpec::from_toml_str(&bad, "m.toml").unwrap_err();
        assert!(matches!(err, MachineError::Parse { .. }), "{err:?}");
    }

    /// Validates `spec` and returns the invalid field's path and the whole message.
    fn invalid_field(spec: &MachineSpec) -> (String, String) {
        match spec.validate("m.toml") {
            Err(e @ MachineError::Invalid { .. }) => {
                let msg = e.to_string();
                let MachineError::Invalid { field, path, .. } = e else {
                    unreachable!()
                };
                assert_eq!(path, "m.toml", "the message names the file");
                assert!(msg.starts_with("m.toml: "), "{msg}");
                assert!(!msg.contains('\n'), "one line: {msg}");
                (field, msg)
            }
            other => panic!("expected an invalid field, got {other:?}"),
        }
    }

    fn text_error(text: &str) -> String {
        match MachineSpec::from_toml_str(text, "m.toml") {
            Ok(_) => panic!("expected a rejected machine file"),
            Err(e) => {
                let msg = e.to_string();
                assert!(
                    msg.starts_with("m.toml: ") && !msg.contains('\n'),
                    "one line naming the file: {msg}"
                );
                msg
            }
        }
    }

    #[test]
    fn the_embedded_reference_machine_loads_validates_and_round_trips_through_toml() {
        let spec = reference();
        spec.validate(REF_PATH).unwrap();
        assert_eq!(MachineSpec::reference(), spec);
        // What the loader reads back from the text it writes is the same machine.
        let text = toml::to_string(&spec).expect("the machine serialises to TOML");
        let back = MachineSpec::from_toml_str(&text, "written.toml").unwrap();
        assert_eq!(back, spec);
    }

    /// 1e-9 mm = 1 pm: float rounding of nominal poses on ~1 m coordinates.
    const POSE_MM: f64 = 1e-9;

    #[test]
    fn the_reference_geometry_puts_the_tool_on_the_head_and_the_workpiece_on_the_table() {
        // A vertical machining centre: the table (X) on the saddle (Y) carries the workpiece, the
        // head (Z) carries a 150 mm tool. Nominally the tip stays on the spindle axis and moves
        // with Z only; the workpiece moves against X and Y; the gauge point is 150 mm above the
        // tip; and the tip lands on the commanded point in the workpiece frame.
        let spec = reference();
        let g = spec.geometry();
        let (lo, hi) = (spec.axes.travel_min_mm, spec.axes.travel_max_mm);
        for corner in 0..8 {
            let q: [f64; 3] =
                std::array::from_fn(|a| if corner >> a & 1 == 0 { lo[a] } else { hi[a] });
            let pose = crate::kinematics::nominal_machine_pose(&g, q);
            let close = |got: nalgebra::Vector3<f64>, want: [f64; 3]| {
                (got - nalgebra::Vector3::from(want)).amax() < POSE_MM
            };
            let tip = pose.bed_from_tool.translation.vector;
            let gauge = pose.bed_from_spindle.translation.vector;
            let work = pose.bed_from_workpiece.translation.vector;
            assert!(close(tip, [0.0, 0.0, q[2] - 150.0]), "{q:?}: tip {tip:?}");
            assert!(close(gauge, [0.0, 0.0, q[2]]), "{q:?}: gauge {gauge:?}");
            assert!(
                close(work, [-q[0], -q[1], -150.0]),
                "{q:?}: workpiece {work:?}"
            );
            let in_work = pose.workpiece_from_tool().translation.vector;
            assert!(close(in_work, q), "{q:?}: tip in the workpiece {in_work:?}");
        }
    }

    #[test]
    fn the_reference_sensors_sit_at_distinct_locations_one_of_them_in_the_air() {
        // Two sensors on one node would read the same temperature twice (collinear inputs); the
        // ambient reading is what the predictors' ambient history feature needs.
        let spec = reference();
        let in_air = spec
            .sensors
            .iter()
            .filter(|s| s.node == crate::thermal::AMBIENT_NODE)
            .count();
        assert_eq!(in_air, 1, "{:?}", spec.sensors);
        let mut nodes: Vec<&str> = spec.sensors.iter().map(|s| s.node.as_str()).collect();
        nodes.sort_unstable();
        nodes.dedup();
        assert_eq!(nodes.len(), spec.sensors.len(), "distinct locations");
    }

    #[test]
    fn a_negative_or_zero_travel_names_the_max_field_of_that_axis() {
        let mut spec = reference();
        spec.axes.travel_max_mm[0] = -10.0;
        let (field, msg) = invalid_field(&spec);
        assert_eq!(field, "axes.travel_max_mm[0]");
        assert!(msg.contains("X travel must be positive"), "{msg}");

        let mut spec = reference();
        spec.axes.travel_min_mm[1] = 400.0; // zero travel on Y
        assert_eq!(invalid_field(&spec).0, "axes.travel_max_mm[1]");

        // Through the text path as well: the message carries the file and the field.
        let text =
            reference_text_with("[axes]", "travel_max_mm = [560.0", "travel_max_mm = [-10.0");
        let msg = text_error(&text);
        assert!(msg.contains("field `axes.travel_max_mm[0]`"), "{msg}");
    }

    #[test]
    fn a_home_outside_the_travel_or_a_non_finite_travel_is_named() {
        let mut spec = reference();
        spec.axes.home_mm[2] = 10.0;
        assert_eq!(invalid_field(&spec).0, "axes.home_mm[2]");
        let mut spec = reference();
        spec.axes.travel_min_mm[1] = f64::NAN;
        assert_eq!(invalid_field(&spec).0, "axes.travel_min_mm[1]");
    }

    #[test]
    fn a_misspelt_field_is_named_with_its_line() {
        let text = reference_text_with("[instruments]", "laser_point_s", "laser_pont_s");
        let msg = text_error(&text);
        assert!(msg.contains("unknown field `laser_pont_s`"), "{msg}");
        let line = 1 + REFERENCE_TOML[..REFERENCE_TOML.find("laser_point_s").unwrap()]
            .matches('\n')
            .count();
        assert!(
            msg.contains(&format!("line {line}")),
            "names line {line}: {msg}"
        );
        let text = reference_text_with("[errors.motion.EXX]", "random_sigma", "random_sigmaa");
        let msg = text_error(&text);
        assert!(msg.contains("random_sigmaa"), "{msg}");
    }

    #[test]
    fn bad_values_in_the_error_field_are_named_by_their_dotted_path() {
        let mut spec = reference();
        spec.errors.motion.get_mut("EBX").unwrap().unit = ValueUnit::Um;
        let (field, msg) = invalid_field(&spec);
        assert_eq!(field, "errors.motion.EBX.unit");
        assert!(msg.contains("\"urad\""), "{msg}");

        let text = reference_text_with("[errors.motion.EBX]", "unit = \"urad\"", "unit = \"um\"");
        assert!(text_error(&text).contains("field `errors.motion.EBX.unit`"));

        let mut spec = reference();
        spec.errors.motion.get_mut("EBX").unwrap().poly[1] = f64::NAN;
        assert_eq!(invalid_field(&spec).0, "errors.motion.EBX.poly[1]");

        let mut spec = reference();
        spec.errors.motion.get_mut("EYY").unwrap().random_sigma = -1.0;
        assert_eq!(invalid_field(&spec).0, "errors.motion.EYY.random_sigma");

        let mut spec = reference();
        spec.errors.motion.remove("EAZ");
        let (field, msg) = invalid_field(&spec);
        assert_eq!(field, "errors.motion.EAZ");
        assert!(msg.contains("missing"), "{msg}");

        let mut spec = reference();
        let p = spec.errors.motion["EXX"].clone();
        spec.errors.motion.insert("EQX".into(), p);
        assert_eq!(invalid_field(&spec).0, "errors.motion.EQX");

        let mut spec = reference();
        spec.errors.squareness.get_mut("EA0Z").unwrap().unit = ValueUnit::Um;
        assert_eq!(invalid_field(&spec).0, "errors.squareness.EA0Z.unit");

        let mut spec = reference();
        spec.errors.random[1].repeatability_sigma_um = -0.1;
        assert_eq!(
            invalid_field(&spec).0,
            "errors.random[1].repeatability_sigma_um"
        );

        let mut spec = reference();
        spec.errors.motion.get_mut("EXX").unwrap().thermal[0].nodes[2] = "x_screw_9".into();
        let (field, msg) = invalid_field(&spec);
        assert_eq!(field, "errors.motion.EXX.thermal[0].nodes[2]");
        assert!(msg.contains("x_screw_9"), "{msg}");
    }

    #[test]
    fn bad_values_in_other_sections_are_named() {
        let mut spec = reference();
        spec.machine.chain = "w X Q b Z t".into();
        assert_eq!(invalid_field(&spec).0, "machine.chain");

        let mut spec = reference();
        spec.tool.diameter_mm = 0.0;
        assert_eq!(invalid_field(&spec).0, "tool.diameter_mm");

        let mut spec = reference();
        spec.instruments.laser_step_mm[2] = 500.0; // Z travel is 450 mm
        assert_eq!(invalid_field(&spec).0, "instruments.laser_step_mm[2]");

        // Thermal and sensor problems: the section is the field, the message the exact path.
        let mut spec = reference();
        spec.thermal.nodes[3].capacity_j_per_k = -1.0;
        let (field, msg) = invalid_field(&spec);
        assert_eq!(field, "thermal");
        assert!(msg.contains("thermal.nodes[3].capacity_j_per_k"), "{msg}");

        let mut spec = reference();
        spec.sensors[4].noise_sigma_degc = -0.1;
        let (field, msg) = invalid_field(&spec);
        assert_eq!(field, "sensors[4]");
        assert!(msg.contains("noise_sigma_degc"), "{msg}");

        let mut spec = reference();
        spec.sensors[0].node = "nowhere".into();
        let (_, msg) = invalid_field(&spec);
        assert!(msg.contains("nowhere") && msg.contains("BXH"), "{msg}");
    }

    /// The reference sensors read their nodes within noise, quantisation and lag through a 1 h
    /// warm-up at 9000 rpm.
    #[test]
    fn reference_sensors_sit_on_their_nodes_and_track_them_through_a_warm_up() {
        use crate::sensors::SensorBank;
        use crate::thermal::{Activity, ThermalNetwork, AMBIENT_NODE};
        let spec = reference();
        let mut net = ThermalNetwork::new(&spec.thermal, 20.0).unwrap();
        let mut bank = SensorBank::new(&spec.sensors, net.node_names(), 11).unwrap();
        bank.update(0.0, net.temps_degc(), 20.0).unwrap();
        // Spindle at 9000 rpm, axes parked mid-travel and moving at the calibration's speeds.
        let duty = Activity {
            spindle_rpm: 9000.0,
            axis_pos_mm: [280.0, 200.0, -225.0],
            axis_speed_mm_per_min: [4000.0, 3000.0, 2000.0],
            coolant: false,
        };
        for _ in 0..3600 {
            net.advance(1.0, &duty).unwrap();
            bank.update(1.0, net.temps_degc(), net.ambient_degc())
                .unwrap();
        }
        let r = bank.read();
        assert_eq!(r.values_degc.len(), spec.sensors.len());
        for s in &spec.sensors {
            let truth = if s.node == AMBIENT_NODE {
                20.0
            } else {
                net.temp_degc(&s.node).unwrap()
            };
            let v = r.value_degc(&s.name).unwrap();
            // Noise σ 0.02 °C, half a quantum 0.031 °C, 20 s lag on a ≤ 0.2 °C/min slope: < 0.2 °C.
            assert!((v - truth).abs() < 0.2, "{}: {v} vs node {truth}", s.name);
        }
        assert!(
            r.value_degc("BYB").unwrap() > 25.0,
            "spindle sensor must have warmed: {r:?}"
        );
    }
}
