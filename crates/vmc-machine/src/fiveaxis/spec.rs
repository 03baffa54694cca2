//! The five-axis machine file (`machines/trunnion-ac.toml`): serde description and validation.

use std::collections::BTreeMap;
use std::path::Path;

use serde::{Deserialize, Serialize};

use crate::errors::spec::ValueUnit;
use crate::errors::ErrorFieldSpec;
use crate::machine::{AxesSpec, MachineError, MachineInfo, ToolSpec};
use crate::motion::{MotionLimits, RotaryAxisLimits, RotaryLimits};
use vmc_identify::chain::{Chain, Geometry, RotaryAxis, RotaryGeometry};

/// One rotary axis: its nominal line and travel limits.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RotarySpec {
    /// `A`, `B` or `C`.
    pub axis: String,
    /// A point of the nominal axis line, bed coordinates at machine zero, mm.
    pub point_mm: [f64; 3],
    /// Lower travel limit, degrees (required).
    pub min_deg: Option<f64>,
    /// Upper travel limit, degrees (required).
    pub max_deg: Option<f64>,
    /// Largest angular speed, deg/s, rapids included; needed to run programs (`run`), not to
    /// probe (no default; a trunnion table of this class: 90 for A, 180 for C).
    #[serde(default)]
    pub max_speed_deg_per_s: Option<f64>,
    /// Largest angular acceleration, deg/s²; needed to run programs, with
    /// `max_speed_deg_per_s` (no default; typical: 360 for A, 720 for C).
    #[serde(default)]
    pub max_accel_deg_per_s2: Option<f64>,
}

/// The reference sphere on the table and the stylus ball.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SphereSpec {
    /// Nominal centre, bed coordinates at machine zero (all axes at zero), mm.
    pub centre_mm: [f64; 3],
    /// Further spheres of the same calibrated artefact (known offsets from the first, e.g. from a
    /// CMM), nominal centres in the same coordinates, mm; default none.
    #[serde(default)]
    pub extra_centres_mm: Vec<[f64; 3]>,
    /// Where a single sphere is put, one block of configurations after another, to probe the
    /// working volume (`probe-campaign`'s placements), nominal centres in the same coordinates,
    /// mm. Only roughly known: identification fits each placement's offset. Default none (the
    /// campaign then spreads its own over the working volume).
    #[serde(default)]
    pub placements_mm: Vec<[f64; 3]>,
    /// Radius of the reference spheres, mm.
    pub radius_mm: f64,
    /// Radius of the stylus ball, mm.
    pub stylus_radius_mm: f64,
}

/// The virtual touch probe.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ProbeSpec {
    /// Trigger noise at 2σ along the approach, µm (default 0.25).
    #[serde(default = "default_noise")]
    pub trigger_noise_2sigma_um: f64,
    /// Points per sphere (default 9; 4 to 9: pole, four at 45°, four at 10° elevation).
    #[serde(default = "default_points")]
    pub points: usize,
    /// Start of each approach outside the contact, mm (default 2).
    #[serde(default = "default_clearance")]
    pub clearance_mm: f64,
}

fn default_noise() -> f64 {
    0.25
}
fn default_points() -> usize {
    9
}
fn default_clearance() -> f64 {
    2.0
}

/// One harmonic of a rotary motion error: `amplitude · cos(order·θ − phase_rad)`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RotaryHarmonicSpec {
    /// Amplitude in the profile's unit.
    pub amplitude: f64,
    /// Periods per turn.
    pub order: u32,
    /// Phase, rad.
    #[serde(default)]
    pub phase_rad: f64,
}

/// A motion error of a rotary axis as a function of its angle.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RotaryProfileSpec {
    /// `um` (translations) or `urad` (rotations).
    pub unit: ValueUnit,
    /// Deterministic harmonics.
    #[serde(default)]
    pub harmonics: Vec<RotaryHarmonicSpec>,
    /// σ of the seeded harmonic amplitudes (cos and sin of each order); 0 = none.
    #[serde(default)]
    pub random_sigma: f64,
    /// Highest seeded order (default 4).
    #[serde(default = "default_orders")]
    pub random_orders: u32,
}

fn default_orders() -> u32 {
    4
}

/// A constant error: value plus a seeded offset.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ConstantSpec {
    /// `um` or `urad`.
    pub unit: ValueUnit,
    /// Value.
    #[serde(default)]
    pub value: f64,
    /// σ of the seeded offset.
    #[serde(default)]
    pub random_sigma: f64,
}

/// The errors of one rotary axis, by ISO 230-7 name.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RotaryErrorsSpec {
    /// The 6 motion errors, e.g. `E_XC … E_CC`.
    pub motion: BTreeMap<String, RotaryProfileSpec>,
    /// The 5 location errors, e.g. `E_X0C, E_Y0C, E_A0C, E_B0C, E_C0C`.
    pub location: BTreeMap<String, ConstantSpec>,
}

/// A five-axis machine description.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FiveAxisSpec {
    /// Name and chain.
    pub machine: MachineInfo,
    /// Linear travels.
    pub axes: AxesSpec,
    /// Kinematic limits of X, Y, Z for running programs (default: [`MotionLimits::default`],
    /// 30 m/min rapids, 10 m/min feed, 2 m/s²).
    #[serde(default)]
    pub motion: MotionLimits,
    /// Rotary axes, in chain order (workpiece to tool).
    pub rotary: Vec<RotarySpec>,
    /// The probe stylus in the spindle.
    pub tool: ToolSpec,
    /// The reference sphere.
    pub sphere: SphereSpec,
    /// The touch probe.
    pub probe: ProbeSpec,
    /// The 21 linear-axis errors (three-axis format; thermal terms are not used).
    pub linear_errors: ErrorFieldSpec,
    /// Rotary-axis errors by axis letter.
    pub rotary_errors: BTreeMap<String, RotaryErrorsSpec>,
    /// Assembly errors: `E_XW, E_YW, E_ZW` (datum), `E_XT, E_YT, E_ZT` (stylus tip), µm.
    pub assembly: BTreeMap<String, ConstantSpec>,
}

/// Names of the 6 motion errors of rotary axis `letter` (`E_XC … E_CC`).
#[must_use]
pub fn motion_names(letter: char) -> [String; 6] {
    ['X', 'Y', 'Z', 'A', 'B', 'C'].map(|c| format!("E_{c}{letter}"))
}

/// Names of the 6 assembly errors.
pub const ASSEMBLY_NAMES: [&str; 6] = ["E_XW", "E_YW", "E_ZW", "E_XT", "E_YT", "E_ZT"];

/// Names of the 5 location errors of rotary axis `axis`.
#[must_use]
pub fn location_names(axis: RotaryAxis) -> Vec<(usize, String)> {
    let l = axis.letter();
    ['X', 'Y', 'Z', 'A', 'B', 'C']
        .iter()
        .enumerate()
        .filter(|(i, _)| *i != axis.index())
        .map(|(i, c)| (i, format!("E_{c}0{l}")))
        .collect()
}

fn invalid(path: &str, field: impl Into<String>, msg: impl Into<String>) -> MachineError {
    MachineError::Invalid {
        path: path.to_string(),
        field: field.into(),
        msg: msg.into(),
    }
}

fn parse_axis(letter: &str) -> Option<RotaryAxis> {
    match letter {
        "A" => Some(RotaryAxis::A),
        "B" => Some(RotaryAxis::B),
        "C" => Some(RotaryAxis::C),
        _ => None,
    }
}

impl FiveAxisSpec {
    /// Reads and validates a five-axis machine file.
    ///
    /// # Errors
    /// An unreadable file, bad TOML, or the first invalid field.
    pub fn load(path: &Path) -> Result<Self, MachineError> {
        let text = crate::machine::read_machine_file(path)?;
        Self::from_toml_str(&text, &path.display().to_string())
    }

    /// Parses and validates; `path` names the file in errors.
    ///
    /// # Errors
    /// Bad TOML or the first invalid field.
    pub fn from_toml_str(text: &str, path: &str) -> Result<Self, MachineError> {
        let spec: FiveAxisSpec = crate::machine::parse_machine_toml(text, path)?;
        spec.validate(path)?;
        Ok(spec)
    }

    /// Checks every section; the error names the first bad field.
    ///
    /// # Errors
    /// [`MachineError::Invalid`].
    pub fn validate(&self, path: &str) -> Result<(), MachineError> {
        let chain = Chain::parse(&self.machine.chain)
            .map_err(|e| invalid(path, "machine.chain", e.to_string()))?;
        for i in 0..3 {
            let (lo, hi) = (self.axes.travel_min_mm[i], self.axes.travel_max_mm[i]);
            if !(lo.is_finite() && hi.is_finite() && lo < hi) {
                return Err(invalid(
                    path,
                    format!("axes.travel_min_mm[{i}]"),
                    "must be finite and below travel_max_mm",
                ));
            }
        }
        let want: Vec<char> = chain.rotary_axes().iter().map(|a| a.letter()).collect();
        for (i, r) in self.rotary.iter().enumerate() {
            let field = |f: &str| format!("rotary[{i}].{f}");
            let Some(axis) = parse_axis(&r.axis) else {
                return Err(invalid(
                    path,
                    field("axis"),
                    format!(
                        "unknown rotary axis letter '{}' (expected A, B or C)",
                        r.axis
                    ),
                ));
            };
            let (Some(lo), Some(hi)) = (r.min_deg, r.max_deg) else {
                return Err(invalid(
                    path,
                    field("min_deg"),
                    format!(
                        "rotary axis {} has no travel limits: give min_deg and max_deg (degrees)",
                        r.axis
                    ),
                ));
            };
            if !(lo.is_finite() && hi.is_finite() && lo < hi) {
                return Err(invalid(
                    path,
                    field("min_deg"),
                    format!("rotary axis {}: min_deg must be below max_deg", r.axis),
                ));
            }
            for (name, v) in [
                ("max_speed_deg_per_s", r.max_speed_deg_per_s),
                ("max_accel_deg_per_s2", r.max_accel_deg_per_s2),
            ] {
                if v.is_some_and(|v| !(v.is_finite() && v > 0.0)) {
                    return Err(invalid(path, field(name), "must be positive and finite"));
                }
            }
            if !r.point_mm.iter().all(|v| v.is_finite()) {
                return Err(invalid(path, field("point_mm"), "must be finite"));
            }
            let errs = self.rotary_errors.get(&r.axis).ok_or_else(|| {
                invalid(
                    path,
                    format!("rotary_errors.{}", r.axis),
                    "missing: give the motion and location errors of this axis",
                )
            })?;
            self.validate_rotary_errors(path, axis, errs)?;
        }
        let got: Vec<char> = self
            .rotary
            .iter()
            .map(|r| r.axis.chars().next().unwrap_or('?'))
            .collect();
        if want != got {
            return Err(invalid(
                path,
                "rotary",
                format!("the chain {chain} has rotary axes {want:?} (in this order) but [[rotary]] describes {got:?}"),
            ));
        }
        for k in self.rotary_errors.keys() {
            if !self.rotary.iter().any(|r| &r.axis == k) {
                return Err(invalid(
                    path,
                    format!("rotary_errors.{k}"),
                    "no such rotary axis in [[rotary]]",
                ));
            }
        }
        for n in ASSEMBLY_NAMES {
            let c = self
                .assembly
                .get(n)
                .ok_or_else(|| invalid(path, format!("assembly.{n}"), "missing"))?;
            check_constant(path, &format!("assembly.{n}"), c, ValueUnit::Um)?;
        }
        if let Some(k) = self
            .assembly
            .keys()
            .find(|k| !ASSEMBLY_NAMES.contains(&k.as_str()))
        {
            return Err(invalid(
                path,
                format!("assembly.{k}"),
                format!("unknown assembly error (expected {ASSEMBLY_NAMES:?})"),
            ));
        }
        let s = &self.sphere;
        if !(s.radius_mm > 0.0
            && s.stylus_radius_mm > 0.0
            && s.radius_mm.is_finite()
            && s.stylus_radius_mm.is_finite())
        {
            return Err(invalid(path, "sphere.radius_mm", "radii must be positive"));
        }
        if !s.extra_centres_mm.iter().flatten().all(|v| v.is_finite()) {
            return Err(invalid(path, "sphere.extra_centres_mm", "must be finite"));
        }
        if !s.placements_mm.iter().flatten().all(|v| v.is_finite()) {
            return Err(invalid(path, "sphere.placements_mm", "must be finite"));
        }
        let p = &self.probe;
        if !(p.trigger_noise_2sigma_um >= 0.0 && p.trigger_noise_2sigma_um.is_finite()) {
            return Err(invalid(
                path,
                "probe.trigger_noise_2sigma_um",
                "must be ≥ 0",
            ));
        }
        if !(4..=9).contains(&p.points) {
            return Err(invalid(
                path,
                "probe.points",
                format!("must be 4 to 9, got {}", p.points),
            ));
        }
        if !(p.clearance_mm > 0.0 && p.clearance_mm.is_finite()) {
            return Err(invalid(path, "probe.clearance_mm", "must be positive"));
        }
        self.motion
            .validate()
            .map_err(|e| invalid(path, "motion", e.to_string()))?;
        self.linear_errors
            .validate(&|_| false)
            .map_err(|e| invalid(path, "linear_errors", e.to_string()))?;
        Ok(())
    }

    fn validate_rotary_errors(
        &self,
        path: &str,
        axis: RotaryAxis,
        errs: &RotaryErrorsSpec,
    ) -> Result<(), MachineError> {
        let l = axis.letter();
        let names = motion_names(l);
        for (c, n) in names.iter().enumerate() {
            let field = format!("rotary_errors.{l}.motion.{n}");
            let m = errs
                .motion
                .get(n)
                .ok_or_else(|| invalid(path, &field, "missing"))?;
            let unit = if c < 3 {
                ValueUnit::Um
            } else {
                ValueUnit::Urad
            };
            if m.unit != unit {
                return Err(invalid(
                    path,
                    &field,
                    format!("unit must be \"{}\"", unit_name(unit)),
                ));
            }
            let positioning = c == 3 + axis.index();
            for h in &m.harmonics {
                if h.order == 0 || (h.order == 1 && !positioning) {
                    return Err(invalid(
                        path,
                        &field,
                        format!("order {} is not allowed: order 0 and (except for the angular positioning error) order 1 belong to the location errors of the average line", h.order),
                    ));
                }
                if !(h.amplitude.is_finite() && h.phase_rad.is_finite()) {
                    return Err(invalid(path, &field, "harmonic values must be finite"));
                }
            }
            if !(m.random_sigma >= 0.0 && m.random_sigma.is_finite()) || m.random_orders > 32 {
                return Err(invalid(
                    path,
                    &field,
                    "random_sigma must be ≥ 0 and random_orders ≤ 32",
                ));
            }
        }
        if let Some(k) = errs.motion.keys().find(|k| !names.contains(k)) {
            return Err(invalid(
                path,
                format!("rotary_errors.{l}.motion.{k}"),
                format!("unknown motion error (expected {names:?})"),
            ));
        }
        let locs = location_names(axis);
        for (c, n) in &locs {
            let field = format!("rotary_errors.{l}.location.{n}");
            let v = errs
                .location
                .get(n)
                .ok_or_else(|| invalid(path, &field, "missing"))?;
            check_constant(
                path,
                &field,
                v,
                if *c < 3 {
                    ValueUnit::Um
                } else {
                    ValueUnit::Urad
                },
            )?;
        }
        if let Some(k) = errs
            .location
            .keys()
            .find(|k| !locs.iter().any(|(_, n)| n == *k))
        {
            let names: Vec<&String> = locs.iter().map(|(_, n)| n).collect();
            return Err(invalid(
                path,
                format!("rotary_errors.{l}.location.{k}"),
                format!("unknown location error (expected {names:?})"),
            ));
        }
        Ok(())
    }

    /// The nominal geometry: what identification is given.
    #[must_use]
    pub fn geometry(&self) -> Geometry {
        Geometry {
            chain: Chain::parse(&self.machine.chain).expect("validated"),
            rotary: self
                .rotary
                .iter()
                .map(|r| RotaryGeometry {
                    axis: parse_axis(&r.axis).expect("validated"),
                    point_mm: r.point_mm,
                })
                .collect(),
            tool_offset_mm: self.tool.offset_mm,
            datum_mm: self.sphere.centre_mm,
        }
    }

    /// Nominal centre of every sphere in the workpiece frame (the first is the datum, at 0), mm.
    #[must_use]
    pub fn sphere_targets_w_mm(&self) -> Vec<[f64; 3]> {
        let c = self.sphere.centre_mm;
        std::iter::once([0.0; 3])
            .chain(
                self.sphere
                    .extra_centres_mm
                    .iter()
                    .map(|e| [e[0] - c[0], e[1] - c[1], e[2] - c[2]]),
            )
            .collect()
    }

    /// Travel limits of the rotary axes, degrees, in [`Geometry::rotary`] order.
    #[must_use]
    pub fn rotary_limits_deg(&self) -> Vec<(f64, f64)> {
        self.rotary
            .iter()
            .map(|r| (r.min_deg.unwrap_or(0.0), r.max_deg.unwrap_or(0.0)))
            .collect()
    }

    /// Travel limits of the rotary axes by G-code letter (A, B, C), degrees; `None` for an axis
    /// the machine lacks.
    #[must_use]
    pub fn rotary_travel_abc_deg(&self) -> [Option<(f64, f64)>; 3] {
        let mut out = [None; 3];
        for r in &self.rotary {
            if let (Some(axis), Some(lo), Some(hi)) = (parse_axis(&r.axis), r.min_deg, r.max_deg) {
                out[axis.index()] = Some((lo, hi));
            }
        }
        out
    }

    /// Speed and acceleration limits of the rotary axes for the planner.
    ///
    /// # Errors
    /// [`MachineError::Invalid`] naming the first rotary axis without them (`path` names the
    /// file).
    pub fn rotary_limits(&self, path: &str) -> Result<RotaryLimits, MachineError> {
        let mut limits = RotaryLimits::default();
        for (i, r) in self.rotary.iter().enumerate() {
            let (Some(axis), Some(speed), Some(accel)) = (
                parse_axis(&r.axis),
                r.max_speed_deg_per_s,
                r.max_accel_deg_per_s2,
            ) else {
                return Err(invalid(
                    path,
                    format!("rotary[{i}].max_speed_deg_per_s"),
                    format!(
                        "rotary axis {} has no speed limits: give max_speed_deg_per_s and max_accel_deg_per_s2 to run programs on this machine",
                        r.axis
                    ),
                ));
            };
            limits.axes[axis.index()] = Some(RotaryAxisLimits {
                max_speed_deg_per_s: speed,
                max_accel_deg_per_s2: accel,
            });
        }
        Ok(limits)
    }

    /// Whether linear axes `q` are within travel (with `margin_mm` inside each limit).
    #[must_use]
    pub fn within_travel(&self, q: [f64; 3], margin_mm: f64) -> bool {
        (0..3).all(|i| {
            q[i] >= self.axes.travel_min_mm[i] + margin_mm
                && q[i] <= self.axes.travel_max_mm[i] - margin_mm
        })
    }
}

fn check_constant(
    path: &str,
    field: &str,
    c: &ConstantSpec,
    unit: ValueUnit,
) -> Result<(), MachineError> {
    if c.unit != unit {
        return Err(invalid(
            path,
            field,
            format!("unit must be \"{}\"", unit_name(unit)),
        ));
    }
    if !(c.value.is_finite() && c.random_sigma >= 0.0 && c.random_sigma.is_finite()) {
        return Err(invalid(
            path,
            field,
            "value must be finite and random_sigma ≥ 0",
        ));
    }
    Ok(())
}

fn unit_name(u: ValueUnit) -> &'static str {
    match u {
        ValueUnit::Um => "um",
        ValueUnit::Urad => "urad",
    }
}
