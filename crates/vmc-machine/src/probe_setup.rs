//! What a setup file says about probing: the touch probe in the spindle (`[probe]`) and the
//! artefacts on the table a probe move may touch (`[[artefacts]]`: gauge blocks, reference
//! spheres), and the solids a probe's ball meets (those artefacts and the setup's fixtures and
//! stock) with their signed distance.
//!
//! **Frame.** Machine coordinates of the interpreter and planner (the commanded tool tip of the
//! machine file's own tool relative to the table, mm), as the setup's bodies. A gauge block is
//! an axis-aligned box hanging from its top face; a sphere is the ball alone (its stem is not
//! modelled). All lengths in mm.

use serde::Deserialize;

use crate::collision_spec::{check_coord, check_size, BodySpec, FieldError, ShapeKind};

/// The `[probe]` section: the touch probe used by every G38 move. A field left out takes the
/// value of `TouchProbe::typical`; the stylus length defaults to the machine's own tool
/// length (the ball's centre is then the commanded tool tip without any tool table); see
/// `Placement::touch_probe`.
#[derive(Debug, Clone, Copy, PartialEq, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ProbeSpec {
    /// Gauge line to ball centre, mm.
    pub stylus_length_mm: Option<f64>,
    /// Ball radius, mm.
    pub ball_radius_mm: Option<f64>,
    /// Force at which the probe trips, N.
    pub trigger_force_n: Option<f64>,
    /// Stylus bending stiffness at the ball, N/µm.
    pub stylus_stiffness_n_per_um: Option<f64>,
    /// Unidirectional repeatability, 2σ, µm.
    pub repeatability_2sigma_um: Option<f64>,
    /// The controller's servo period, s.
    pub servo_period_s: Option<f64>,
}

impl ProbeSpec {
    /// Checks every given field (`probe.…` in errors).
    pub fn validate(&self) -> Result<(), FieldError> {
        let fields = [
            ("stylus_length_mm", self.stylus_length_mm, false, 1e4),
            ("ball_radius_mm", self.ball_radius_mm, false, 1e3),
            ("trigger_force_n", self.trigger_force_n, true, 1e3),
            (
                "stylus_stiffness_n_per_um",
                self.stylus_stiffness_n_per_um,
                false,
                1e6,
            ),
            (
                "repeatability_2sigma_um",
                self.repeatability_2sigma_um,
                true,
                1e3,
            ),
            ("servo_period_s", self.servo_period_s, true, 1.0),
        ];
        for (name, value, zero_ok, max) in fields {
            let Some(v) = value else { continue };
            let ok = v.is_finite() && v <= max && (v > 0.0 || (zero_ok && v == 0.0));
            if !ok {
                let low = if zero_ok { "[0" } else { "(0" };
                return Err((
                    format!("probe.{name}"),
                    format!("must be a finite number in {low}, {max}], got {v}"),
                ));
            }
        }
        Ok(())
    }
}

/// Kind of artefact.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ArtefactKind {
    /// A gauge block (`top_mm`: centre of its top face; `size_mm`: X, Y widths and height).
    GaugeBlock,
    /// A reference sphere (`centre_mm`, `radius_mm`).
    Sphere,
}

/// One `[[artefacts]]` entry.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ArtefactSpec {
    /// Name in reports.
    pub name: String,
    /// Gauge block or sphere.
    pub kind: ArtefactKind,
    /// Gauge block: centre of the top face, mm.
    #[serde(default)]
    pub top_mm: Option<[f64; 3]>,
    /// Gauge block: width in X, width in Y, height (down from the top), mm.
    #[serde(default)]
    pub size_mm: Option<[f64; 3]>,
    /// Sphere: centre, mm.
    #[serde(default)]
    pub centre_mm: Option<[f64; 3]>,
    /// Sphere: radius, mm.
    #[serde(default)]
    pub radius_mm: Option<f64>,
    /// A reference: thermally stable and standing where the setup says (its geometry
    /// qualified), so that a probe move touching it measures the machine's drift (`run
    /// --compensate` updates its drift estimate from it). Default false.
    #[serde(default)]
    pub reference: bool,
}

impl ArtefactSpec {
    /// Checks the entry; `prefix` is its dotted path (`artefacts[1]`).
    pub fn validate(&self, prefix: &str) -> Result<(), FieldError> {
        if self.name.trim().is_empty() {
            return Err((format!("{prefix}.name"), "must not be empty".into()));
        }
        let need = |name: &str, given: bool| -> Result<(), FieldError> {
            if given {
                Ok(())
            } else {
                Err((
                    format!("{prefix}.{name}"),
                    format!("missing: a {} needs `{name}`", self.kind_name()),
                ))
            }
        };
        let forbid = |name: &str, given: bool| -> Result<(), FieldError> {
            if given {
                Err((
                    format!("{prefix}.{name}"),
                    format!("not a field of a {}", self.kind_name()),
                ))
            } else {
                Ok(())
            }
        };
        match self.kind {
            ArtefactKind::GaugeBlock => {
                need("top_mm", self.top_mm.is_some())?;
                need("size_mm", self.size_mm.is_some())?;
                forbid("centre_mm", self.centre_mm.is_some())?;
                forbid("radius_mm", self.radius_mm.is_some())?;
                check_coord(format!("{prefix}.top_mm"), self.top_mm.unwrap_or_default())?;
                let size = self.size_mm.unwrap_or_default();
                for (i, s) in size.iter().enumerate() {
                    check_size(format!("{prefix}.size_mm[{i}]"), *s)?;
                }
            }
            ArtefactKind::Sphere => {
                need("centre_mm", self.centre_mm.is_some())?;
                need("radius_mm", self.radius_mm.is_some())?;
                forbid("top_mm", self.top_mm.is_some())?;
                forbid("size_mm", self.size_mm.is_some())?;
                check_coord(
                    format!("{prefix}.centre_mm"),
                    self.centre_mm.unwrap_or_default(),
                )?;
                check_size(format!("{prefix}.radius_mm"), self.radius_mm.unwrap_or(0.0))?;
            }
        }
        Ok(())
    }

    fn kind_name(&self) -> &'static str {
        match self.kind {
            ArtefactKind::GaugeBlock => "gauge_block",
            ArtefactKind::Sphere => "sphere",
        }
    }

    /// Its solid (a validated entry).
    pub fn solid(&self) -> Solid {
        match self.kind {
            ArtefactKind::GaugeBlock => {
                let top = self.top_mm.unwrap_or_default();
                let size = self.size_mm.unwrap_or_default();
                Solid::Box {
                    min_mm: [
                        top[0] - 0.5 * size[0],
                        top[1] - 0.5 * size[1],
                        top[2] - size[2],
                    ],
                    max_mm: [top[0] + 0.5 * size[0], top[1] + 0.5 * size[1], top[2]],
                }
            }
            ArtefactKind::Sphere => Solid::Sphere {
                centre_mm: self.centre_mm.unwrap_or_default(),
                radius_mm: self.radius_mm.unwrap_or(0.0),
            },
        }
    }
}

/// Checks a list of artefacts (`artefacts[k]…` in errors), names unique.
pub fn validate_artefacts(artefacts: &[ArtefactSpec]) -> Result<(), FieldError> {
    for (k, a) in artefacts.iter().enumerate() {
        let p = format!("artefacts[{k}]");
        a.validate(&p)?;
        if artefacts[..k].iter().any(|o| o.name == a.name) {
            return Err((
                format!("{p}.name"),
                format!("duplicate artefact name \"{}\"", a.name),
            ));
        }
    }
    Ok(())
}

/// A solid a probe's ball can touch, in machine coordinates, mm.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Solid {
    /// Axis-aligned box.
    Box {
        /// Lowest corner.
        min_mm: [f64; 3],
        /// Highest corner.
        max_mm: [f64; 3],
    },
    /// Vertical cylinder.
    Cylinder {
        /// Centre of the bottom face.
        base_center_mm: [f64; 3],
        /// Radius.
        radius_mm: f64,
        /// Height along +Z.
        height_mm: f64,
    },
    /// Sphere.
    Sphere {
        /// Centre.
        centre_mm: [f64; 3],
        /// Radius.
        radius_mm: f64,
    },
}

impl Solid {
    /// The solid of a validated body.
    pub fn of_body(b: &BodySpec) -> Self {
        match b.shape {
            ShapeKind::Box => Solid::Box {
                min_mm: b.min_mm.unwrap_or_default(),
                max_mm: b.max_mm.unwrap_or_default(),
            },
            ShapeKind::Cylinder => Solid::Cylinder {
                base_center_mm: b.base_center_mm.unwrap_or_default(),
                radius_mm: b.radius_mm.unwrap_or(0.0),
                height_mm: b.height_mm.unwrap_or(0.0),
            },
        }
    }

    /// Signed distance from `p_mm` to the solid's surface, mm: > 0 outside, < 0 inside (exact).
    pub fn signed_distance_mm(&self, p_mm: [f64; 3]) -> f64 {
        match *self {
            Solid::Box { min_mm, max_mm } => {
                // Per axis: distance outside the slab (> 0) or minus the depth inside (< 0).
                let d = [0, 1, 2].map(|a| {
                    let c = 0.5 * (min_mm[a] + max_mm[a]);
                    (p_mm[a] - c).abs() - 0.5 * (max_mm[a] - min_mm[a])
                });
                let outside = d.iter().map(|v| v.max(0.0).powi(2)).sum::<f64>().sqrt();
                let inside = d[0].max(d[1]).max(d[2]).min(0.0);
                outside + inside
            }
            Solid::Cylinder {
                base_center_mm,
                radius_mm,
                height_mm,
            } => {
                let dr =
                    (p_mm[0] - base_center_mm[0]).hypot(p_mm[1] - base_center_mm[1]) - radius_mm;
                let zc = base_center_mm[2] + 0.5 * height_mm;
                let dz = (p_mm[2] - zc).abs() - 0.5 * height_mm;
                dr.max(0.0).hypot(dz.max(0.0)) + dr.max(dz).min(0.0)
            }
            Solid::Sphere {
                centre_mm,
                radius_mm,
            } => {
                let d2: f64 = (0..3).map(|a| (p_mm[a] - centre_mm[a]).powi(2)).sum();
                d2.sqrt() - radius_mm
            }
        }
    }
}

/// A solid with the name reports give it.
#[derive(Debug, Clone, PartialEq)]
pub struct NamedSolid {
    /// Name (the artefact's or the body's).
    pub name: String,
    /// Shape.
    pub solid: Solid,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn signed_distances_are_exact_outside_and_inside() {
        let b = Solid::Box {
            min_mm: [0.0, 0.0, 0.0],
            max_mm: [10.0, 20.0, 30.0],
        };
        assert_eq!(b.signed_distance_mm([5.0, 10.0, 35.0]), 5.0);
        assert_eq!(b.signed_distance_mm([5.0, 10.0, 29.0]), -1.0);
        assert!((b.signed_distance_mm([13.0, 24.0, 15.0]) - 5.0).abs() < 1e-12);
        let c = Solid::Cylinder {
            base_center_mm: [0.0, 0.0, 0.0],
            radius_mm: 5.0,
            height_mm: 10.0,
        };
        assert!((c.signed_distance_mm([8.0, 0.0, 5.0]) - 3.0).abs() < 1e-12);
        assert!((c.signed_distance_mm([0.0, 0.0, 9.0]) + 1.0).abs() < 1e-12);
        assert!((c.signed_distance_mm([9.0, 0.0, 13.0]) - 5.0).abs() < 1e-12);
        let s = Solid::Sphere {
            centre_mm: [1.0, 1.0, 1.0],
            radius_mm: 2.0,
        };
        assert!((s.signed_distance_mm([1.0, 1.0, 5.0]) - 2.0).abs() < 1e-12);
    }

    #[test]
    fn a_gauge_block_hangs_from_its_top_face() {
        let a = ArtefactSpec {
            name: "block".into(),
            kind: ArtefactKind::GaugeBlock,
            top_mm: Some([100.0, 50.0, -300.0]),
            size_mm: Some([30.0, 20.0, 50.0]),
            centre_mm: None,
            radius_mm: None,
            reference: false,
        };
        assert_eq!(a.validate("artefacts[0]"), Ok(()));
        assert_eq!(
            a.solid(),
            Solid::Box {
                min_mm: [85.0, 40.0, -350.0],
                max_mm: [115.0, 60.0, -300.0]
            }
        );
        let bad = ArtefactSpec {
            radius_mm: Some(3.0),
            ..a.clone()
        };
        assert_eq!(
            bad.validate("artefacts[0]").unwrap_err().0,
            "artefacts[0].radius_mm"
        );
        let flat = ArtefactSpec {
            size_mm: Some([30.0, 0.0, 50.0]),
            ..a
        };
        assert_eq!(
            flat.validate("artefacts[2]").unwrap_err().0,
            "artefacts[2].size_mm[1]"
        );
    }
}
