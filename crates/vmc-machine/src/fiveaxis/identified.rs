//! The identified model of a five-axis machine as `identify` writes it (`identified.json`),
//! read back for compensation.
//!
//! The file lists every parameter of the fitted set by name (`E_Y0A`, `E_CC·cos2C`, …) with its
//! value in µm or µrad; parameters that could not be separated are there with the value the
//! identification gave them (merged or fixed at 0). The set is rebuilt from the machine's
//! nominal geometry (location and assembly errors, plus each rotary axis's motion harmonics up to
//! the highest order named for that axis) and must list the same names in the same order, so a file of another
//! machine or of another parameter set is refused rather than misread. Values are converted to
//! mm and rad.
//!
//! This is knowledge: the identified parameters only, never the twin's truth.

use serde::Deserialize;
use thiserror::Error;

use vmc_identify::chain::{Geometry, Pose};
use vmc_identify::errors::{ErrorState, ParameterSet};

/// Why an identified-model file cannot be used.
#[derive(Debug, Error)]
pub enum IdentifiedError {
    /// Not the JSON `identify` writes.
    #[error("not an identified model (the JSON `identify` writes): {0}")]
    Json(String),
    /// Identified on another machine.
    #[error(
        "identified on machine {file}, not {machine}: its parameters do not describe this machine"
    )]
    OtherMachine {
        /// Machine named in the file.
        file: String,
        /// The machine run.
        machine: String,
    },
    /// The parameter list is not a set this machine's geometry gives.
    #[error("the parameters do not match machine {machine}'s parameter set: {why}")]
    Parameters {
        /// The machine.
        machine: String,
        /// The first difference.
        why: String,
    },
}

#[derive(Debug, Deserialize)]
struct FileParameter {
    name: String,
    unit: String,
    value: f64,
}

#[derive(Debug, Deserialize)]
struct File {
    machine: String,
    parameters: Vec<FileParameter>,
}

/// An identified model: the parameter set and its values (mm, rad).
#[derive(Debug, Clone, PartialEq)]
pub struct IdentifiedModel {
    /// The parameters, in the file's order.
    pub set: ParameterSet,
    /// Their values, mm or rad.
    pub values: Vec<f64>,
    /// Highest harmonic order of the rotary motion errors fitted over the axes (0: none).
    pub harmonics: u32,
}

/// Highest harmonic order named in `name` (`E_CC·cos2C` → 2), if it is a harmonic.
fn harmonic_order(name: &str) -> Option<u32> {
    let (_, f) = name.split_once('·')?;
    let digits: String = f
        .trim_start_matches("cos")
        .trim_start_matches("sin")
        .chars()
        .take_while(char::is_ascii_digit)
        .collect();
    digits.parse().ok()
}

impl IdentifiedModel {
    /// Reads the JSON text of `identify`'s output for `machine` of nominal geometry `geom`.
    ///
    /// # Errors
    /// Bad JSON, another machine's file, a parameter list this geometry does not give, a unit
    /// that does not fit its parameter or a value that is not finite.
    pub fn from_json_str(
        text: &str,
        machine: &str,
        geom: &Geometry,
    ) -> Result<Self, IdentifiedError> {
        let file: File =
            serde_json::from_str(text).map_err(|e| IdentifiedError::Json(e.to_string()))?;
        if file.machine != machine {
            return Err(IdentifiedError::OtherMachine {
                file: file.machine,
                machine: machine.to_string(),
            });
        }
        let bad = |why: String| IdentifiedError::Parameters {
            machine: machine.to_string(),
            why,
        };
        // Highest order named per rotary axis (the axis letter ends the name: `E_XC·cos2C`).
        let mut orders = vec![0_u32; geom.rotary.len()];
        for p in &file.parameters {
            if let Some(k) = harmonic_order(&p.name) {
                let letter = p.name.chars().last();
                if let Some(r) = geom
                    .rotary
                    .iter()
                    .position(|r| Some(r.axis.letter()) == letter)
                {
                    orders[r] = orders[r].max(k);
                }
            }
        }
        let harmonics = orders.iter().copied().max().unwrap_or(0);
        // The offsets of a relocated sphere's placements (`E_XP1` …) follow the machine's
        // errors; read back to keep the list whole, they act on no compensation.
        let placements = file
            .parameters
            .iter()
            .filter(|p| p.name.starts_with("E_XP"))
            .count();
        let set = ParameterSet::location_and_assembly(geom)
            .with_motion_harmonics_per_axis(geom, &orders)
            .with_placements(placements);
        let names = set.names();
        if names.len() != file.parameters.len() {
            return Err(bad(format!(
                "{} parameters in the file, {} expected",
                file.parameters.len(),
                names.len()
            )));
        }
        let mut values = Vec::with_capacity(names.len());
        for ((p, want), param) in file.parameters.iter().zip(&names).zip(&set.params) {
            if &p.name != want {
                return Err(bad(format!("found {}, expected {want}", p.name)));
            }
            let (unit, k) = if param.component.is_angle() {
                ("urad", 1e-6)
            } else {
                ("um", 1e-3)
            };
            if p.unit != unit {
                return Err(bad(format!(
                    "{} is in \"{}\", expected \"{unit}\"",
                    p.name, p.unit
                )));
            }
            if !p.value.is_finite() {
                return Err(bad(format!("{} is not a finite number", p.name)));
            }
            values.push(p.value * k);
        }
        Ok(IdentifiedModel {
            set,
            values,
            harmonics,
        })
    }

    /// The errors the model predicts at `pose` (all others zero).
    #[must_use]
    pub fn state_at(&self, pose: &Pose) -> ErrorState {
        self.set.state_at(&self.values, pose)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fiveaxis::FiveAxisSpec;

    fn spec() -> FiveAxisSpec {
        FiveAxisSpec::from_toml_str(
            include_str!("../../../../machines/trunnion-ac.toml"),
            "trunnion-ac.toml",
        )
        .unwrap()
    }

    fn file_of(set: &ParameterSet, values: &[f64], machine: &str) -> String {
        let params: Vec<String> = set
            .params
            .iter()
            .zip(values)
            .map(|(p, v)| {
                let (unit, k) = if p.component.is_angle() {
                    ("urad", 1e6)
                } else {
                    ("um", 1e3)
                };
                format!(
                    r#"{{"name": "{}", "unit": "{unit}", "value": {}}}"#,
                    p.name(),
                    v * k
                )
            })
            .collect();
        format!(
            r#"{{"machine": "{machine}", "rank": 15, "parameters": [{}]}}"#,
            params.join(", ")
        )
    }

    #[test]
    fn a_written_model_reads_back_with_its_harmonics_and_values_in_mm_and_rad() {
        let s = spec();
        let g = s.geometry();
        let set = ParameterSet::location_and_assembly(&g).with_motion_harmonics(&g, 3);
        let values: Vec<f64> = (0..set.len()).map(|i| (i as f64 - 30.0) * 1e-6).collect();
        let m = IdentifiedModel::from_json_str(
            &file_of(&set, &values, "trunnion-ac"),
            "trunnion-ac",
            &g,
        )
        .unwrap();
        assert_eq!(m.harmonics, 3);
        assert_eq!(m.set, set);
        for (a, b) in m.values.iter().zip(&values) {
            assert!((a - b).abs() < 1e-15, "{a} vs {b}");
        }
        let pose = Pose {
            linear_mm: [10.0, -20.0, -100.0],
            rotary_deg: [90.0, -30.0],
        };
        let tip = |st: &ErrorState| vmc_identify::htm::tip_in_workpiece_mm(&g, &pose, st);
        // 1e-12 mm: the µm/µrad round trip of the values.
        assert!((tip(&m.state_at(&pose)) - tip(&set.state_at(&values, &pose))).norm() < 1e-12);
    }

    #[test]
    fn a_model_with_other_orders_per_axis_reads_back_with_them() {
        let s = spec();
        let g = s.geometry();
        let set =
            ParameterSet::location_and_assembly(&g).with_motion_harmonics_per_axis(&g, &[3, 0]);
        let values: Vec<f64> = (0..set.len()).map(|i| i as f64 * 1e-6).collect();
        let m = IdentifiedModel::from_json_str(
            &file_of(&set, &values, "trunnion-ac"),
            "trunnion-ac",
            &g,
        )
        .unwrap();
        // C: 6 errors × orders 2, 3 × (cos, sin) and order 1 of E_CC.
        assert_eq!((m.harmonics, m.set.len()), (3, 19 + 26));
        assert_eq!(m.set, set);
    }

    #[test]
    fn another_machine_or_parameter_list_is_refused() {
        let s = spec();
        let g = s.geometry();
        let set = ParameterSet::location_and_assembly(&g);
        let values = vec![0.0; set.len()];
        let e =
            IdentifiedModel::from_json_str(&file_of(&set, &values, "hermle"), "trunnion-ac", &g)
                .unwrap_err();
        assert!(
            e.to_string().contains("identified on machine hermle"),
            "{e}"
        );
        let mut short = set.clone();
        short.params.pop();
        let e = IdentifiedModel::from_json_str(
            &file_of(&short, &values, "trunnion-ac"),
            "trunnion-ac",
            &g,
        )
        .unwrap_err();
        assert!(
            e.to_string()
                .contains("18 parameters in the file, 19 expected"),
            "{e}"
        );
        let e = IdentifiedModel::from_json_str("{", "trunnion-ac", &g).unwrap_err();
        assert!(e.to_string().contains("not an identified model"), "{e}");
    }
}
