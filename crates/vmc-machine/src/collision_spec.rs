//! Collision geometry descriptions (TOML): the machine file's optional `[collision]` section and
//! fixture files. Every validation error names its field by dotted path
//! (`bodies[2].radius_mm`), as the machine loader does.
//!
//! All coordinates are in the machine frame of the interpreter and planner: the commanded tool
//! tip relative to the table (ISO 841), mm. Bodies fixed to the table (the table itself, vises,
//! stock) are static in that frame; the collision module checks motion against them.

use std::path::Path;

use serde::{Deserialize, Serialize};
use thiserror::Error;

/// Largest coordinate or size accepted in a collision description (mm): keeps every shape
/// query finite and rejects unit mistakes (metres typed as µm).
pub const MAX_COORD_MM: f64 = 1.0e5;

/// A collision description that cannot be used.
#[derive(Debug, Error)]
pub enum CollisionSpecError {
    /// The file could not be read.
    #[error("{path}: cannot read fixture file: {err}")]
    Io {
        /// The file.
        path: String,
        /// Why.
        err: std::io::Error,
    },
    /// Not valid TOML or not the schema (the parser's message has line and column).
    #[error("{path}: {msg}")]
    Parse {
        /// The file.
        path: String,
        /// The TOML parser's message.
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

/// What a static body is: decides which contacts are crashes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum BodyRole {
    /// The machine table: any contact is a crash.
    Table,
    /// Vise, clamps, fixture plates: any contact is a crash.
    Fixture,
    /// The workpiece blank: the tool may cut it at feed (G1/G2/G3) with the spindle running.
    Stock,
}

impl BodyRole {
    /// Lower-case name used in reports.
    pub fn name(self) -> &'static str {
        match self {
            BodyRole::Table => "table",
            BodyRole::Fixture => "fixture",
            BodyRole::Stock => "stock",
        }
    }
}

/// Shape of a static body.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ShapeKind {
    /// Axis-aligned box given by `min_mm` and `max_mm`.
    Box,
    /// Vertical (Z-axis) cylinder given by `base_center_mm`, `radius_mm` and `height_mm`.
    Cylinder,
}

/// One static body fixed to the table.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BodySpec {
    /// Name used in reports (e.g. `"vise_fixed_jaw"`).
    pub name: String,
    /// Table, fixture or stock.
    pub role: BodyRole,
    /// `"box"` or `"cylinder"`.
    pub shape: ShapeKind,
    /// Box: lowest corner, mm.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub min_mm: Option<[f64; 3]>,
    /// Box: highest corner, mm.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_mm: Option<[f64; 3]>,
    /// Cylinder: centre of the bottom face, mm.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub base_center_mm: Option<[f64; 3]>,
    /// Cylinder: radius, mm.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub radius_mm: Option<f64>,
    /// Cylinder: height along +Z, mm.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub height_mm: Option<f64>,
}

/// A coaxial cylinder on the spindle axis (holder, spindle nose).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SpindleCylinder {
    /// Diameter, mm.
    pub diameter_mm: f64,
    /// Length along the spindle axis, mm.
    pub length_mm: f64,
}

/// The machine file's optional `[collision]` section: what moves with the head, and the table.
///
/// The tool is the machine's `[tool]` (length `|tool.offset_mm[2]|` from the gauge point to the
/// tip, `tool.diameter_mm`). The holder hangs `holder.length_mm` below the gauge point, so the
/// exposed tool is the cylinder from the tip up to the holder; the spindle nose rises
/// `spindle_nose.length_mm` above the gauge point.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CollisionSpec {
    /// Tool holder below the gauge point.
    pub holder: SpindleCylinder,
    /// Spindle nose above the gauge point.
    pub spindle_nose: SpindleCylinder,
    /// Bodies that are part of the machine (usually the table).
    #[serde(default)]
    pub bodies: Vec<BodySpec>,
}

/// A fixture file: bodies clamped on the table for one job (vise, stock).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FixtureSpec {
    /// Bodies, in the machine frame.
    pub bodies: Vec<BodySpec>,
}

/// A field error before the file name is attached: (dotted field, message).
pub type FieldError = (String, String);

pub(crate) fn check_coord(field: String, v: [f64; 3]) -> Result<(), FieldError> {
    for (i, c) in v.iter().enumerate() {
        if !(c.is_finite() && c.abs() <= MAX_COORD_MM) {
            return Err((
                format!("{field}[{i}]"),
                format!("must be a finite number within ±{MAX_COORD_MM} mm, got {c}"),
            ));
        }
    }
    Ok(())
}

pub(crate) fn check_size(field: String, v: f64) -> Result<(), FieldError> {
    if v.is_finite() && v > 0.0 && v <= MAX_COORD_MM {
        Ok(())
    } else {
        Err((
            field,
            format!("must be a finite number in (0, {MAX_COORD_MM}] mm, got {v}"),
        ))
    }
}

fn required<T: Copy>(prefix: &str, name: &str, v: Option<T>, shape: &str) -> Result<T, FieldError> {
    v.ok_or_else(|| {
        (
            format!("{prefix}.{name}"),
            format!("missing: a {shape} needs `{name}`"),
        )
    })
}

fn forbidden<T>(prefix: &str, name: &str, v: &Option<T>, shape: &str) -> Result<(), FieldError> {
    if v.is_some() {
        Err((
            format!("{prefix}.{name}"),
            format!("not a field of a {shape}"),
        ))
    } else {
        Ok(())
    }
}

impl BodySpec {
    /// Checks the body; `prefix` is its dotted path (`bodies[2]`).
    pub fn validate(&self, prefix: &str) -> Result<(), FieldError> {
        if self.name.trim().is_empty() {
            return Err((format!("{prefix}.name"), "must not be empty".into()));
        }
        match self.shape {
            ShapeKind::Box => {
                let lo = required(prefix, "min_mm", self.min_mm, "box")?;
                let hi = required(prefix, "max_mm", self.max_mm, "box")?;
                forbidden(prefix, "base_center_mm", &self.base_center_mm, "box")?;
                forbidden(prefix, "radius_mm", &self.radius_mm, "box")?;
                forbidden(prefix, "height_mm", &self.height_mm, "box")?;
                check_coord(format!("{prefix}.min_mm"), lo)?;
                check_coord(format!("{prefix}.max_mm"), hi)?;
                for i in 0..3 {
                    if hi[i] <= lo[i] {
                        return Err((
                            format!("{prefix}.max_mm[{i}]"),
                            format!("must be above min_mm[{i}] = {} mm, got {}", lo[i], hi[i]),
                        ));
                    }
                }
            }
            ShapeKind::Cylinder => {
                let c = required(prefix, "base_center_mm", self.base_center_mm, "cylinder")?;
                let r = required(prefix, "radius_mm", self.radius_mm, "cylinder")?;
                let h = required(prefix, "height_mm", self.height_mm, "cylinder")?;
                forbidden(prefix, "min_mm", &self.min_mm, "cylinder")?;
                forbidden(prefix, "max_mm", &self.max_mm, "cylinder")?;
                check_coord(format!("{prefix}.base_center_mm"), c)?;
                check_size(format!("{prefix}.radius_mm"), r)?;
                check_size(format!("{prefix}.height_mm"), h)?;
            }
        }
        Ok(())
    }
}

pub(crate) fn validate_bodies(bodies: &[BodySpec], prefix: &str) -> Result<(), FieldError> {
    for (k, b) in bodies.iter().enumerate() {
        let p = format!("{prefix}[{k}]");
        b.validate(&p)?;
        if bodies[..k].iter().any(|o| o.name == b.name) {
            return Err((
                format!("{p}.name"),
                format!("duplicate body name \"{}\"", b.name),
            ));
        }
    }
    Ok(())
}

impl CollisionSpec {
    /// Checks the section against the machine's tool (`tool_offset_mm`); fields are named
    /// `collision.…` (or `tool.offset_mm[i]` when the tool does not fit the holder).
    pub fn validate(&self, tool_offset_mm: [f64; 3]) -> Result<(), FieldError> {
        for (name, c) in [
            ("holder", &self.holder),
            ("spindle_nose", &self.spindle_nose),
        ] {
            check_size(format!("collision.{name}.diameter_mm"), c.diameter_mm)?;
            check_size(format!("collision.{name}.length_mm"), c.length_mm)?;
        }
        for (i, &off_mm) in tool_offset_mm.iter().take(2).enumerate() {
            if off_mm != 0.0 {
                return Err((
                    format!("tool.offset_mm[{i}]"),
                    "the collision check models a tool on the spindle axis: must be 0".into(),
                ));
            }
        }
        let tool_len_mm = -tool_offset_mm[2];
        if tool_len_mm <= self.holder.length_mm {
            return Err((
                "collision.holder.length_mm".into(),
                format!(
                    "must be shorter than the tool length (−tool.offset_mm[2] = {tool_len_mm} mm), got {}",
                    self.holder.length_mm
                ),
            ));
        }
        validate_bodies(&self.bodies, "collision.bodies")
    }
}

impl FixtureSpec {
    /// Reads and validates a fixture file.
    pub fn load(path: &Path) -> Result<Self, CollisionSpecError> {
        let name = path.display().to_string();
        let text = crate::read::read_text(path).map_err(|err| CollisionSpecError::Io {
            path: name.clone(),
            err,
        })?;
        Self::from_toml_str(&text, &name)
    }

    /// Parses and validates fixture text; `path` names it in errors.
    pub fn from_toml_str(text: &str, path: &str) -> Result<Self, CollisionSpecError> {
        let spec: FixtureSpec = toml::from_str(text).map_err(|e| CollisionSpecError::Parse {
            path: path.to_string(),
            msg: crate::read::one_line_toml_error(&e),
        })?;
        validate_bodies(&spec.bodies, "bodies").map_err(|(field, msg)| {
            CollisionSpecError::Invalid {
                path: path.to_string(),
                field,
                msg,
            }
        })?;
        Ok(spec)
    }
}
