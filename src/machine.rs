//! Machine descriptions (`machines/*.toml`, DESIGN §4): loading and validation.
//!
//! One file describes one machine: kinematic chain and travels, tool, motion limits, thermal
//! network, temperature sensors, virtual instruments and the geometric error field. The reference
//! machine `machines/vmc-reference.toml` is embedded in the binary so the main command needs no
//! arguments. Every validation error names the offending field by its dotted path
//! (`axes.travel_max_mm[1]`), so a user can fix their file without reading code.

use std::path::Path;

use serde::{Deserialize, Serialize};
use thiserror::Error;

use crate::errors::ErrorFieldSpec;
use crate::motion::MotionLimits;
use crate::predict::synthesis::{Chain, MachineGeometry};
use crate::sensors::SensorSpec;
use crate::thermal::ThermalSpec;

/// The embedded reference machine description.
pub const REFERENCE_TOML: &str = include_str!("../machines/vmc-reference.toml");

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

/// Virtual instruments of the calibration campaign (DESIGN §6).
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
}

fn invalid(path: &str, field: impl Into<String>, msg: impl Into<String>) -> MachineError {
    MachineError::Invalid {
        path: path.to_string(),
        field: field.into(),
        msg: msg.into(),
    }
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
        let text = std::fs::read_to_string(path).map_err(|err| MachineError::Io {
            path: path.display().to_string(),
            err,
        })?;
        Self::from_toml_str(&text, &path.display().to_string())
    }

    /// Parses and validates a machine description; `path` names it in errors.
    pub fn from_toml_str(text: &str, path: &str) -> Result<Self, MachineError> {
        let spec: MachineSpec = toml::from_str(text).map_err(|e| MachineError::Parse {
            path: path.to_string(),
            msg: e.to_string().trim_end().replace('\n', " "),
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
            if !(st.is_finite() && st > 0.0 && st <= span) {
                return Err(invalid(
                    path,
                    format!("instruments.laser_step_mm[{i}]"),
                    format!("must be in (0, travel = {span} mm], got {st}"),
                ));
            }
        }
        if !(s.laser_point_s.is_finite() && s.laser_point_s > 0.0) {
            return Err(invalid(path, "instruments.laser_point_s", "must be > 0"));
        }
        Ok(())
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
