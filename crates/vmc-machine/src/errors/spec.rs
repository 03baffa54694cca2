//! The serde description of the error field, as written in a machine file, and its validation.

use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

use super::ErrorSpecError;

/// Unit of an error value in the machine file.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum ValueUnit {
    /// Micrometres, for translation errors and spindle translations.
    #[serde(rename = "um")]
    Um,
    /// Microradians, for rotation, squareness and spindle tilt errors.
    #[serde(rename = "urad")]
    Urad,
}

/// How a thermal term's effective temperature is spread along the axis.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ThermalShape {
    /// Same value at every position: `gain · ΔT`.
    Constant,
    /// Grows linearly from the travel minimum: `gain · ΔT · u`, u ∈ [0, 1].
    Linear,
    /// A bow vanishing at both travel ends: `gain · ΔT · 4u(1 − u)`.
    Bow,
    /// Ballscrew expansion: `sign · gain · ∫ (T_seg(s) − T_ref) ds / 1000` from the fixed end to
    /// the position, `gain` in µm/(K·m), segments `nodes` ordered from the travel minimum up.
    Screw,
}

/// Which end of a ballscrew is axially fixed (the expansion grows away from it).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum FixedEnd {
    /// Fixed at the travel minimum (the default).
    #[default]
    Min,
    /// Fixed at the travel maximum.
    Max,
}

/// One thermal contribution to an error: an effective temperature of named thermal nodes times
/// a gain, spread along the axis by `shape`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ThermalTermSpec {
    /// Spatial shape of the term.
    pub shape: ThermalShape,
    /// Gain of a linear error's term (shapes other than `screw`), µm/K. Exactly one gain is
    /// given, the one of the term's shape and the profile's unit.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub gain_um_per_k: Option<f64>,
    /// Gain of an angular error's term, µrad/K.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub gain_urad_per_k: Option<f64>,
    /// Gain of a `screw` term (expansion of the screw), µm per (K·m) of screw.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub gain_um_per_k_m: Option<f64>,
    /// For non-screw shapes: ΔT_eff = Σ weight · (T_node − T_ref). Weights summing to zero make a
    /// pure gradient term.
    #[serde(default)]
    pub weights: BTreeMap<String, f64>,
    /// For `screw`: the segment nodes, ordered from the travel minimum to the maximum.
    #[serde(default)]
    pub nodes: Vec<String>,
    /// For `screw`: the axially fixed end (default `min`).
    #[serde(default)]
    pub fixed_end: FixedEnd,
}

/// A low harmonic of a static profile: `amplitude · sin(2π · cycles · u + phase_rad)`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct HarmonicSpec {
    /// Amplitude in the profile's unit.
    pub amplitude: f64,
    /// Number of periods over the full travel.
    pub cycles: f64,
    /// Phase, rad.
    #[serde(default)]
    pub phase_rad: f64,
}

/// One position-dependent error of an axis (ISO 230-1 motion error): a static profile plus
/// thermal terms. The position is normalised `u = (pos − min) / (max − min)` over the travel.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ProfileSpec {
    /// Unit of every value of this profile: `um` for translations, `urad` for rotations.
    pub unit: ValueUnit,
    /// Polynomial coefficients in u, constant first.
    #[serde(default)]
    pub poly: Vec<f64>,
    /// Low harmonics.
    #[serde(default)]
    pub harmonics: Vec<HarmonicSpec>,
    /// σ of the seeded smooth random part (cubic spline through random knots); 0 = none.
    #[serde(default)]
    pub random_sigma: f64,
    /// Number of random knots over the travel (≥ 2 when `random_sigma` > 0; default 6).
    #[serde(default = "default_knots")]
    pub random_knots: usize,
    /// Amplitude of seeded short-wavelength ripple finer than a calibration step; 0 = none.
    #[serde(default)]
    pub fine_amplitude: f64,
    /// Wavelength of that ripple, mm (default 12 mm).
    #[serde(default = "default_fine_wavelength")]
    pub fine_wavelength_mm: f64,
    /// Thermal terms.
    #[serde(default)]
    pub thermal: Vec<ThermalTermSpec>,
}

fn default_knots() -> usize {
    6
}

fn default_fine_wavelength() -> f64 {
    12.0
}

/// A position-independent error (squareness or spindle drift): a static value plus thermal terms
/// (their shapes must be `constant`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ConstantErrorSpec {
    /// Unit of the values: `um` or `urad` as the error requires.
    pub unit: ValueUnit,
    /// Value at the reference temperature.
    #[serde(default)]
    pub value: f64,
    /// σ of a seeded random offset added to `value` (machine-to-machine spread); 0 = none.
    #[serde(default)]
    pub random_sigma: f64,
    /// Thermal terms (shape `constant`).
    #[serde(default)]
    pub thermal: Vec<ThermalTermSpec>,
}

/// Random, non-systematic error parts of one axis.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AxisRandomSpec {
    /// Non-repeatability: σ of an independent Gaussian error added to the positioning error at
    /// each approach, µm (the study's machines: 0.2–0.5 µm).
    pub repeatability_sigma_um: f64,
    /// Reversal (backlash-like) error, µm: the positioning error is offset by +r/2 after a
    /// positive and −r/2 after a negative approach.
    pub reversal_um: f64,
}

/// The whole error field of a machine, as written in its file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ErrorFieldSpec {
    /// Reference temperature of the static profiles, °C (default 20).
    #[serde(default = "default_ref")]
    pub ref_temp_degc: f64,
    /// The 18 motion errors by ISO 230-1 name (EXX, EYX, EZX, EAX, EBX, ECX, EXY … ECZ).
    pub motion: BTreeMap<String, ProfileSpec>,
    /// The 3 squareness errors by ISO 230-1 name: EC0Y (X–Y), EB0Z (X–Z), EA0Z (Y–Z).
    pub squareness: BTreeMap<String, ConstantErrorSpec>,
    /// The 5 spindle thermal drifts: EXS, EYS, EZS (µm), EAS, EBS (µrad).
    pub spindle: BTreeMap<String, ConstantErrorSpec>,
    /// Non-repeatability and reversal for X, Y, Z.
    pub random: [AxisRandomSpec; 3],
}

fn default_ref() -> f64 {
    20.0
}

/// The 18 ISO 230-1 motion-error names in order: axis-major (X, Y, Z), then δx, δy, δz, εx, εy, εz.
pub const MOTION_NAMES: [[&str; 6]; 3] = [
    ["EXX", "EYX", "EZX", "EAX", "EBX", "ECX"],
    ["EXY", "EYY", "EZY", "EAY", "EBY", "ECY"],
    ["EXZ", "EYZ", "EZZ", "EAZ", "EBZ", "ECZ"],
];
/// Squareness names: α_xy, α_xz, α_yz.
pub const SQUARENESS_NAMES: [&str; 3] = ["EC0Y", "EB0Z", "EA0Z"];
/// Spindle drift names: δx, δy, δz (µm), εx, εy (µrad).
pub const SPINDLE_NAMES: [&str; 5] = ["EXS", "EYS", "EZS", "EAS", "EBS"];

fn unit_for(component: usize) -> ValueUnit {
    if component < 3 {
        ValueUnit::Um
    } else {
        ValueUnit::Urad
    }
}

fn bad(field: String, msg: impl Into<String>) -> ErrorSpecError {
    ErrorSpecError::Field {
        field,
        msg: msg.into(),
    }
}

fn check_finite(field: &str, v: f64) -> Result<(), ErrorSpecError> {
    if v.is_finite() {
        Ok(())
    } else {
        Err(bad(
            field.to_string(),
            format!("must be a finite number, got {v}"),
        ))
    }
}

impl ThermalTermSpec {
    /// The term's gain in the unit of its field (the one given; 0 if none, which validation
    /// refuses).
    pub fn gain(&self) -> f64 {
        self.gain_um_per_k
            .or(self.gain_urad_per_k)
            .or(self.gain_um_per_k_m)
            .unwrap_or(0.0)
    }

    /// The name of the gain field a term of this shape takes in a profile of `unit`.
    fn gain_field(&self, unit: ValueUnit) -> &'static str {
        match (self.shape, unit) {
            (ThermalShape::Screw, _) => "gain_um_per_k_m",
            (_, ValueUnit::Um) => "gain_um_per_k",
            (_, ValueUnit::Urad) => "gain_urad_per_k",
        }
    }

    fn validate(
        &self,
        field: &str,
        unit: ValueUnit,
        constant_only: bool,
        has_node: &dyn Fn(&str) -> bool,
    ) -> Result<(), ErrorSpecError> {
        let want = self.gain_field(unit);
        let given = [
            ("gain_um_per_k", self.gain_um_per_k),
            ("gain_urad_per_k", self.gain_urad_per_k),
            ("gain_um_per_k_m", self.gain_um_per_k_m),
        ];
        for (name, value) in given {
            match value {
                Some(_) if name != want => {
                    return Err(bad(
                        format!("{field}.{name}"),
                        format!("this term's gain is `{want}` (its shape and its error's unit)"),
                    ))
                }
                Some(v) => check_finite(&format!("{field}.{name}"), v)?,
                None if name == want => return Err(bad(format!("{field}.{want}"), "missing")),
                None => {}
            }
        }
        if self.shape == ThermalShape::Screw && unit != ValueUnit::Um {
            return Err(bad(
                format!("{field}.shape"),
                "a screw term expands a linear error (µm)",
            ));
        }
        if constant_only && self.shape != ThermalShape::Constant {
            return Err(bad(
                format!("{field}.shape"),
                "must be \"constant\" for a position-independent error",
            ));
        }
        if self.shape == ThermalShape::Screw {
            if self.nodes.is_empty() {
                return Err(bad(
                    format!("{field}.nodes"),
                    "a screw term needs its segment nodes",
                ));
            }
            if !self.weights.is_empty() {
                return Err(bad(
                    format!("{field}.weights"),
                    "a screw term takes `nodes`, not `weights`",
                ));
            }
            for (i, n) in self.nodes.iter().enumerate() {
                if !has_node(n) {
                    return Err(bad(
                        format!("{field}.nodes[{i}]"),
                        format!("unknown thermal node \"{n}\""),
                    ));
                }
            }
        } else {
            if self.weights.is_empty() {
                return Err(bad(
                    format!("{field}.weights"),
                    "needs at least one node weight",
                ));
            }
            if !self.nodes.is_empty() {
                return Err(bad(
                    format!("{field}.nodes"),
                    "only a screw term takes `nodes`",
                ));
            }
            for (n, w) in &self.weights {
                check_finite(&format!("{field}.weights.{n}"), *w)?;
                if !has_node(n) {
                    return Err(bad(
                        format!("{field}.weights.{n}"),
                        format!("unknown thermal node \"{n}\""),
                    ));
                }
            }
        }
        Ok(())
    }
}

fn check_unit(field: &str, got: ValueUnit, want: ValueUnit) -> Result<(), ErrorSpecError> {
    if got == want {
        Ok(())
    } else {
        let w = if want == ValueUnit::Um { "um" } else { "urad" };
        Err(bad(
            format!("{field}.unit"),
            format!("must be \"{w}\" for this error"),
        ))
    }
}

impl ErrorFieldSpec {
    /// Checks names, units, finiteness and node references. `has_node` tells whether a thermal
    /// node of that name exists. Field paths in errors start at `errors.`.
    pub fn validate(&self, has_node: &dyn Fn(&str) -> bool) -> Result<(), ErrorSpecError> {
        check_finite("errors.ref_temp_degc", self.ref_temp_degc)?;
        for name in self.motion.keys() {
            if !MOTION_NAMES.iter().flatten().any(|n| n == name) {
                return Err(bad(
                    format!("errors.motion.{name}"),
                    "not an ISO 230-1 motion error of X, Y or Z",
                ));
            }
        }
        for (axis, names) in MOTION_NAMES.iter().enumerate() {
            let _ = axis;
            for (c, name) in names.iter().enumerate() {
                let field = format!("errors.motion.{name}");
                let p = self
                    .motion
                    .get(*name)
                    .ok_or_else(|| bad(field.clone(), "missing"))?;
                check_unit(&field, p.unit, unit_for(c))?;
                for (i, v) in p.poly.iter().enumerate() {
                    check_finite(&format!("{field}.poly[{i}]"), *v)?;
                }
                for (i, h) in p.harmonics.iter().enumerate() {
                    let hf = format!("{field}.harmonics[{i}]");
                    check_finite(&format!("{hf}.amplitude"), h.amplitude)?;
                    check_finite(&format!("{hf}.phase_rad"), h.phase_rad)?;
                    if !(h.cycles.is_finite() && h.cycles > 0.0 && h.cycles <= 50.0) {
                        return Err(bad(
                            format!("{hf}.cycles"),
                            format!("must be in (0, 50], got {}", h.cycles),
                        ));
                    }
                }
                if !(p.random_sigma.is_finite() && p.random_sigma >= 0.0) {
                    return Err(bad(
                        format!("{field}.random_sigma"),
                        format!("must be ≥ 0, got {}", p.random_sigma),
                    ));
                }
                if p.random_sigma > 0.0 && !(2..=200).contains(&p.random_knots) {
                    return Err(bad(
                        format!("{field}.random_knots"),
                        format!("must be in 2..=200, got {}", p.random_knots),
                    ));
                }
                if !(p.fine_amplitude.is_finite() && p.fine_amplitude >= 0.0) {
                    return Err(bad(
                        format!("{field}.fine_amplitude"),
                        format!("must be ≥ 0, got {}", p.fine_amplitude),
                    ));
                }
                if !(p.fine_wavelength_mm.is_finite() && p.fine_wavelength_mm >= 0.5) {
                    return Err(bad(
                        format!("{field}.fine_wavelength_mm"),
                        format!("must be ≥ 0.5 mm, got {}", p.fine_wavelength_mm),
                    ));
                }
                for (i, t) in p.thermal.iter().enumerate() {
                    t.validate(&format!("{field}.thermal[{i}]"), p.unit, false, has_node)?;
                }
            }
        }
        self.validate_constants(
            "squareness",
            &self.squareness,
            &SQUARENESS_NAMES,
            |_| ValueUnit::Urad,
            has_node,
        )?;
        self.validate_constants("spindle", &self.spindle, &SPINDLE_NAMES, unit_for, has_node)?;
        for (a, r) in self.random.iter().enumerate() {
            let f = format!("errors.random[{a}]");
            if !(r.repeatability_sigma_um.is_finite() && r.repeatability_sigma_um >= 0.0) {
                return Err(bad(
                    format!("{f}.repeatability_sigma_um"),
                    "must be a finite number ≥ 0",
                ));
            }
            if !(r.reversal_um.is_finite() && r.reversal_um >= 0.0) {
                return Err(bad(
                    format!("{f}.reversal_um"),
                    "must be a finite number ≥ 0",
                ));
            }
        }
        Ok(())
    }

    fn validate_constants(
        &self,
        group: &str,
        map: &BTreeMap<String, ConstantErrorSpec>,
        names: &[&str],
        unit: impl Fn(usize) -> ValueUnit,
        has_node: &dyn Fn(&str) -> bool,
    ) -> Result<(), ErrorSpecError> {
        for name in map.keys() {
            if !names.contains(&name.as_str()) {
                return Err(bad(
                    format!("errors.{group}.{name}"),
                    format!("unknown name; expected one of {}", names.join(", ")),
                ));
            }
        }
        for (i, name) in names.iter().enumerate() {
            let field = format!("errors.{group}.{name}");
            let c = map
                .get(*name)
                .ok_or_else(|| bad(field.clone(), "missing"))?;
            check_unit(&field, c.unit, unit(i))?;
            check_finite(&format!("{field}.value"), c.value)?;
            if !(c.random_sigma.is_finite() && c.random_sigma >= 0.0) {
                return Err(bad(
                    format!("{field}.random_sigma"),
                    "must be a finite number ≥ 0",
                ));
            }
            for (k, t) in c.thermal.iter().enumerate() {
                t.validate(&format!("{field}.thermal[{k}]"), c.unit, true, has_node)?;
            }
        }
        Ok(())
    }
}
