//! Virtual temperature sensors (thermistors) on thermal-network nodes (DESIGN §4, §6).
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
//! (DESIGN §3): plain names and values, no node temperatures, no parameters.

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
        if !seen.insert(s.name.as_str()) {
            return Err(SensorError::DuplicateName {
                index: i,
                name: s.name.clone(),
            });
        }
        if s.node != AMBIENT_NODE && !node_names.iter().any(|n| *n == s.node) {
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
    primed: bool,
    rng: StdRng,
    readings: SensorReadings,
}

impl SensorBank {
    /// Builds a bank for `specs` on a network with `node_names`; noise drawn from `seed`.
    pub fn new(specs: &[SensorSpec], node_names: &[String], seed: u64) -> Result<Self, SensorError> {
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
            primed: false,
            rng: StdRng::seed_from_u64(seed),
        })
    }

    /// Sensor names, in reading order.
    #[must_use]
    pub fn names(&self) -> &Arc<[String]> {
        &self.names
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
        for (i, spec) in self.specs.iter().enumerate() {
            let input = match self.inputs[i] {
                Input::Node(n) => node_temps_degc[n],
                Input::Ambient => ambient_degc,
            };
            let lag = &mut self.lag_degc[i];
            if !self.primed || spec.time_constant_s == 0.0 {
                *lag = input;
            } else {
                *lag += (input - *lag) * -(-dt_s / spec.time_constant_s).exp_m1();
            }
            // Always draw, so the noise stream does not depend on which sensors have σ = 0.
            let z: f64 = StandardNormal.sample(&mut self.rng);
            let noisy = *lag + spec.noise_sigma_degc * z;
            let r = spec.resolution_degc;
            let quantised = if r > 0.0 { (noisy / r).round() * r } else { noisy };
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
