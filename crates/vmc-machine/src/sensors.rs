//! Virtual temperature sensors (thermistors) on thermal-network nodes.
//!
//! Each sensor reads one node (or the prescribed ambient, node name `ambient`) through, in order:
//! 1. a first-order lag, `τ dy/dt = T − y`, integrated exactly for T held over the step:
//!    `y ← y + (T − y)·(1 − e^(−dt/τ))` (τ = 0: no lag; the lag starts at the first reading's
//!    input, i.e. the sensor has been in place long enough to match its node);
//! 2. additive Gaussian noise of standard deviation σ (°C), drawn from the bank's own seeded RNG;
//! 3. quantisation to the resolution, `round(v/r)·r` (default 0.0625 °C, the study's
//!    thermistors), then clamping to the measuring range (default −20…120 °C).
//!
//! [`SensorReadings`] is the only thing that crosses the information boundary at run time
//!: plain names and values, no node temperatures, no parameters.

use crate::thermal::AMBIENT_NODE;
use rand::rngs::StdRng;
use rand::SeedableRng;
use rand_distr::{Distribution, StandardNormal};
use serde::{Deserialize, Serialize};
use std::collections::HashSet;
use std::sync::Arc;
use thiserror::Error;

/// Errors in a sensor description or in the data fed to a sensor bank.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum SensorError {
    /// A sensor names a node that the thermal network does not have.
    #[error("sensors[{index}] ({sensor}) names unknown node `{node}`")]
    UnknownNode {
        /// Position of the sensor in the list.
        index: usize,
        /// Sensor name.
        sensor: String,
        /// The unknown node name.
        node: String,
    },
    /// A numeric field is out of its allowed range.
    #[error("{field} must be {requirement}, got {got}")]
    InvalidValue {
        /// Path of the field, e.g. `sensors[2].noise_sigma_degc`.
        field: String,
        /// What the value must satisfy.
        requirement: &'static str,
        /// The offending value, formatted.
        got: String,
    },
    /// A name that cannot serve as a column name (`<name>_degc` in datasets) and model field.
    #[error(
        "sensors[{index}].name = `{name}`: a sensor name must be non-empty and made of ASCII \
         letters, digits, `_`, `-` and `.` (it becomes the dataset column `<name>_degc`)"
    )]
    BadName {
        /// Position of the sensor in the list.
        index: usize,
        /// The name.
        name: String,
    },
    /// Two sensors share a name.
    #[error("sensors[{index}].name = `{name}` is a duplicate")]
    DuplicateName {
        /// Position of the second occurrence.
        index: usize,
        /// The repeated name.
        name: String,
    },
}

fn default_resolution_degc() -> f64 {
    0.0625
}

fn default_range_degc() -> [f64; 2] {
    [-20.0, 120.0]
}

/// One temperature sensor.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SensorSpec {
    /// Sensor name (e.g. `BXH`), as the predictor knows it.
    pub name: String,
    /// Thermal node it is attached to, or `ambient`.
    pub node: String,
    /// Standard deviation of the additive noise (°C), ≥ 0 (default `0.0`).
    #[serde(default)]
    pub noise_sigma_degc: f64,
    /// First-order lag time constant (s), ≥ 0 (default `0.0`: no lag).
    #[serde(default)]
    pub time_constant_s: f64,
    /// Quantisation step (°C), ≥ 0, 0 = none (default `0.0625`, 12-bit thermistor interface).
    #[serde(default = "default_resolution_degc")]
    pub resolution_degc: f64,
    /// Measuring range `[min, max]` (°C); readings are clamped to it (default `[-20, 120]`).
    #[serde(default = "default_range_degc")]
    pub range_degc: [f64; 2],
}

impl SensorSpec {
    /// Checks the numeric fields; `index` is the sensor's position for the error path.
    pub fn validate(&self, index: usize) -> Result<(), SensorError> {
        let f = |name: &str| format!("sensors[{index}].{name}");
        let bad = |field: String, requirement, v: f64| SensorError::InvalidValue {
            field,
            requirement,
            got: v.to_string(),
        };
        if !(self.noise_sigma_degc.is_finite() && self.noise_sigma_degc >= 0.0) {
            return Err(bad(f("noise_sigma_degc"), ">= 0", self.noise_sigma_degc));
        }
        if !(self.time_constant_s.is_finite() && self.time_constant_s >= 0.0) {
            return Err(bad(f("time_constant_s"), ">= 0", self.time_constant_s));
        }
        if !(self.resolution_degc.is_finite() && self.resolution_degc >= 0.0) {
            return Err(bad(f("resolution_degc"), ">= 0", self.resolution_degc));
        }
        let [lo, hi] = self.range_degc;
        if !lo.is_finite() {
            return Err(bad(f("range_degc[0]"), "finite", lo));
        }
        if !(hi.is_finite() && hi > lo) {
            return Err(bad(f("range_degc[1]"), "finite and > range_degc[0]", hi));
        }
        Ok(())
    }
}

/// Checks a sensor list against the thermal network's node names.
pub fn validate_sensors(specs: &[SensorSpec], node_names: &[String]) -> Result<(), SensorError> {
    let mut seen = HashSet::new();
    for (i, s) in specs.iter().enumerate() {
        let usable = !s.name.is_empty()
            && s.name
                .chars()
                .all(|c| c.is_ascii_alphanumeric() || matches!(c, '_' | '-' | '.'));
        if !usable {
            return Err(SensorError::BadName {
                index: i,
                name: s.name.clone(),
            });
        }
        if !seen.insert(s.name.as_str()) {
            return Err(SensorError::DuplicateName {
                index: i,
                name: s.name.clone(),
            });
        }
        if s.node != AMBIENT_NODE && !node_names.contains(&s.node) {
            return Err(SensorError::UnknownNode {
                index: i,
                sensor: s.name.clone(),
                node: s.node.clone(),
            });
        }
        s.validate(i)?;
    }
    Ok(())
}

/// One set of sensor values at one instant: the run-time information crossing to the predictor.
#[derive(Debug, Clone, PartialEq)]
pub struct SensorReadings {
    /// Time of the readings (s since the bank started).
    pub time_s: f64,
    /// Sensor names, in the order of `values_degc` (shared, not copied per reading).
    pub names: Arc<[String]>,
    /// Readings (°C), quantised and clamped; NaN before the bank's first update.
    pub values_degc: Vec<f64>,
}

impl SensorReadings {
    /// Reading (°C) of the named sensor.
    #[must_use]
    pub fn value_degc(&self, name: &str) -> Option<f64> {
        self.names
            .iter()
            .position(|n| n == name)
            .map(|i| self.values_degc[i])
    }
}

/// Where a sensor takes its input from.
#[derive(Debug, Clone, Copy)]
enum Input {
    Node(usize),
    Ambient,
}

/// A set of sensors with their lag states and their own seeded noise generator.
#[derive(Debug)]
pub struct SensorBank {
    names: Arc<[String]>,
    inputs: Vec<Input>,
    specs: Vec<SensorSpec>,
    node_count: usize,
    lag_degc: Vec<f64>,
    /// Lag gains `1 − e^(−dt/τ)` for the step `lag_gain_dt_bits` (steps repeat: computed once).
    lag_gain: Vec<f64>,
    lag_gain_dt_bits: Option<u64>,
    primed: bool,
    rng: StdRng,
    readings: SensorReadings,
}

impl SensorBank {
    /// Builds a bank for `specs` on a network with `node_names`; noise drawn from `seed`.
    pub fn new(
        specs: &[SensorSpec],
        node_names: &[String],
        seed: u64,
    ) -> Result<Self, SensorError> {
        validate_sensors(specs, node_names)?;
        let inputs = specs
            .iter()
            .map(|s| match node_names.iter().position(|n| *n == s.node) {
                Some(i) => Input::Node(i),
                None => Input::Ambient, // validated: the only other allowed name
            })
            .collect();
        let names: Arc<[String]> = specs.iter().map(|s| s.name.clone()).collect();
        Ok(Self {
            readings: SensorReadings {
                time_s: 0.0,
                names: Arc::clone(&names),
                values_degc: vec![f64::NAN; specs.len()],
            },
            names,
            inputs,
            specs: specs.to_vec(),
            node_count: node_names.len(),
            lag_degc: vec![f64::NAN; specs.len()],
            lag_gain: vec![0.0; specs.len()],
            lag_gain_dt_bits: None,
            primed: false,
            rng: StdRng::seed_from_u64(seed),
        })
    }

    /// Sensor names, in reading order.
    #[must_use]
    pub fn names(&self) -> &Arc<[String]> {
        &self.names
    }

    /// Forgets the sensors' lag: the next [`Self::update`] reads its temperatures as settled
    /// (as the first one does).
    pub fn settle(&mut self) {
        self.primed = false;
    }

    /// Advances the sensors by `dt_s` with node temperatures and ambient (°C) held over the step,
    /// and takes a new reading (lag, then noise, then quantisation and range clamp).
    pub fn update(
        &mut self,
        dt_s: f64,
        node_temps_degc: &[f64],
        ambient_degc: f64,
    ) -> Result<(), SensorError> {
        let bad = |field: &str, requirement, got: String| SensorError::InvalidValue {
            field: field.to_owned(),
            requirement,
            got,
        };
        if !(dt_s.is_finite() && dt_s >= 0.0) {
            return Err(bad("dt_s", ">= 0", dt_s.to_string()));
        }
        if node_temps_degc.len() != self.node_count {
            return Err(bad(
                "node_temps_degc.len()",
                "equal to the network's node count",
                node_temps_degc.len().to_string(),
            ));
        }
        if !ambient_degc.is_finite() {
            return Err(bad("ambient_degc", "finite", ambient_degc.to_string()));
        }
        if self.lag_gain_dt_bits != Some(dt_s.to_bits()) {
            for (g, spec) in self.lag_gain.iter_mut().zip(&self.specs) {
                *g = if spec.time_constant_s == 0.0 {
                    1.0
                } else {
                    -(-dt_s / spec.time_constant_s).exp_m1()
                };
            }
            self.lag_gain_dt_bits = Some(dt_s.to_bits());
        }
        for (i, spec) in self.specs.iter().enumerate() {
            let input = match self.inputs[i] {
                Input::Node(n) => node_temps_degc[n],
                Input::Ambient => ambient_degc,
            };
            let lag = &mut self.lag_degc[i];
            if !self.primed || spec.time_constant_s == 0.0 {
                *lag = input;
            } else {
                *lag += (input - *lag) * self.lag_gain[i];
            }
            // Always draw, so the noise stream does not depend on which sensors have σ = 0.
            let z: f64 = StandardNormal.sample(&mut self.rng);
            let noisy = *lag + spec.noise_sigma_degc * z;
            let r = spec.resolution_degc;
            let quantised = if r > 0.0 {
                (noisy / r).round() * r
            } else {
                noisy
            };
            self.readings.values_degc[i] = quantised.clamp(spec.range_degc[0], spec.range_degc[1]);
        }
        self.primed = true;
        self.readings.time_s += dt_s;
        Ok(())
    }

    /// The latest readings (NaN values before the first [`Self::update`]).
    #[must_use]
    pub fn read(&self) -> SensorReadings {
        self.readings.clone()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sensor(name: &str, node: &str, sigma: f64, tau: f64) -> SensorSpec {
        SensorSpec {
            name: name.into(),
            node: node.into(),
            noise_sigma_degc: sigma,
            time_constant_s: tau,
            resolution_degc: 0.0625,
            range_degc: [-20.0, 120.0],
        }
    }

    fn nodes() -> Vec<String> {
        vec!["a".into(), "b".into()]
    }

    #[test]
    fn a_name_that_cannot_be_a_column_name_is_refused() {
        for bad in ["", "a,b", "x y", "t\"1", "é"] {
            let err = validate_sensors(&[sensor(bad, "a", 0.0, 0.0)], &nodes()).unwrap_err();
            assert_eq!(
                err,
                SensorError::BadName {
                    index: 0,
                    name: bad.into()
                }
            );
        }
        for good in ["BXH", "z_screw_1", "t1.front-left"] {
            assert!(validate_sensors(&[sensor(good, "a", 0.0, 0.0)], &nodes()).is_ok());
        }
    }

    #[test]
    fn lagged_sensor_reaches_63_percent_of_a_step_after_one_time_constant() {
        let mut bank = SensorBank::new(&[sensor("S", "a", 0.0, 60.0)], &nodes(), 1).unwrap();
        bank.update(0.0, &[20.0, 0.0], 20.0).unwrap();
        assert_eq!(bank.read().values_degc, [20.0]);
        for _ in 0..60 {
            bank.update(1.0, &[30.0, 0.0], 20.0).unwrap();
        }
        let r = bank.read();
        // 20 + 10·(1 − e⁻¹) = 26.32 °C, read to within half a quantisation step (0.03125 °C).
        assert!((r.values_degc[0] - 26.321).abs() <= 0.0313, "{r:?}");
        assert!((r.time_s - 60.0).abs() < 1e-12);
        for _ in 0..600 {
            bank.update(1.0, &[30.0, 0.0], 20.0).unwrap();
        }
        assert_eq!(bank.read().values_degc, [30.0]);
    }

    #[test]
    fn readings_are_quantised_to_0_0625_degc_steps_and_clamped_to_the_range() {
        let specs = [sensor("A", "a", 0.0, 0.0), sensor("B", "b", 0.0, 0.0)];
        let mut bank = SensorBank::new(&specs, &nodes(), 1).unwrap();
        bank.update(1.0, &[20.03, 20.04], 20.0).unwrap();
        assert_eq!(bank.read().values_degc, [20.0, 20.0625]);
        bank.update(1.0, &[150.0, -40.0], 20.0).unwrap();
        assert_eq!(bank.read().values_degc, [120.0, -20.0]);
        // With noise every reading still sits on the 0.0625 °C grid.
        let mut noisy = SensorBank::new(&[sensor("N", "a", 0.3, 5.0)], &nodes(), 7).unwrap();
        for k in 0..200 {
            noisy
                .update(1.0, &[20.0 + 0.01 * k as f64, 0.0], 20.0)
                .unwrap();
            let v = noisy.read().values_degc[0];
            assert_eq!((v / 0.0625).fract(), 0.0, "{v}");
        }
    }

    fn trace(seed: u64) -> Vec<u64> {
        let specs = [
            sensor("A", "a", 0.2, 10.0),
            sensor("Amb", "ambient", 0.2, 0.0),
        ];
        let mut bank = SensorBank::new(&specs, &nodes(), seed).unwrap();
        let mut out = Vec::new();
        for k in 0..100 {
            bank.update(1.0, &[25.0 + 0.001 * k as f64, 0.0], 20.0)
                .unwrap();
            out.extend(bank.read().values_degc.iter().map(|v| v.to_bits()));
        }
        out
    }

    #[test]
    fn same_seed_gives_the_same_bits_and_another_seed_other_noise() {
        let (a, b, c) = (trace(42), trace(42), trace(43));
        assert_eq!(a, b);
        let differing = a.iter().zip(&c).filter(|(x, y)| x != y).count();
        // σ = 0.2 °C is 3.2 quantisation steps: most readings must differ between seeds.
        assert!(differing > 100, "only {differing} of 200 readings differ");
    }

    #[test]
    fn noise_has_the_stated_standard_deviation() {
        let mut bank = SensorBank::new(&[sensor("A", "a", 0.5, 0.0)], &nodes(), 3).unwrap();
        let n = 20_000;
        let (mut sum, mut sum2) = (0.0, 0.0);
        for _ in 0..n {
            bank.update(1.0, &[50.0, 0.0], 20.0).unwrap();
            let e = bank.read().values_degc[0] - 50.0;
            sum += e;
            sum2 += e * e;
        }
        let mean = sum / n as f64;
        let sd = (sum2 / n as f64 - mean * mean).sqrt();
        // Standard error of σ over 20 000 draws ≈ 0.0025 °C; quantisation adds r²/12 in variance.
        assert!(
            mean.abs() < 0.02 && (sd - 0.5).abs() < 0.015,
            "mean {mean} sd {sd}"
        );
    }

    #[test]
    fn ambient_sensor_reads_the_ambient_temperature() {
        let mut bank = SensorBank::new(&[sensor("Amb", "ambient", 0.0, 0.0)], &nodes(), 1).unwrap();
        bank.update(1.0, &[80.0, 80.0], 21.5).unwrap();
        assert_eq!(bank.read().value_degc("Amb"), Some(21.5));
        assert_eq!(bank.read().value_degc("BXH"), None);
    }

    #[test]
    fn unknown_node_error_names_the_sensor_and_the_node() {
        let err = SensorBank::new(&[sensor("XD", "x_motr", 0.0, 0.0)], &nodes(), 1).unwrap_err();
        assert_eq!(
            err.to_string(),
            "sensors[0] (XD) names unknown node `x_motr`"
        );
    }

    #[test]
    fn invalid_fields_are_named_in_the_error() {
        let mut s = sensor("ZH", "a", -0.1, 0.0);
        let err = validate_sensors(&[s.clone()], &nodes())
            .unwrap_err()
            .to_string();
        assert_eq!(err, "sensors[0].noise_sigma_degc must be >= 0, got -0.1");
        s.noise_sigma_degc = 0.0;
        s.range_degc = [50.0, 10.0];
        let err = validate_sensors(&[s.clone()], &nodes())
            .unwrap_err()
            .to_string();
        assert!(err.starts_with("sensors[0].range_degc[1]"), "{err}");
        s.range_degc = [-20.0, 120.0];
        let err = validate_sensors(&[s.clone(), s], &nodes())
            .unwrap_err()
            .to_string();
        assert!(err.contains("sensors[1].name"), "{err}");
    }

    #[test]
    fn wrong_node_count_is_an_error() {
        let mut bank = SensorBank::new(&[sensor("A", "a", 0.0, 0.0)], &nodes(), 1).unwrap();
        assert!(bank.update(1.0, &[20.0], 20.0).is_err());
        assert!(
            bank.read().values_degc[0].is_nan(),
            "no reading before a valid update"
        );
    }

    #[test]
    fn toml_sensor_gets_the_thermistor_defaults_and_rejects_unknown_fields() {
        let s: SensorSpec = toml::from_str("name = \"ZT\"\nnode = \"work_zone\"").unwrap();
        assert_eq!(s.resolution_degc, 0.0625);
        assert_eq!(s.range_degc, [-20.0, 120.0]);
        assert_eq!(s.noise_sigma_degc, 0.0);
        assert!(toml::from_str::<SensorSpec>("name = \"ZT\"\nnode = \"w\"\nsigma = 1.0").is_err());
    }
}
