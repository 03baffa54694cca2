//! A thermal state given as fixed sensor readings (`BXH=24.1,BYH=23.0,…`), and how a model is
//! brought to it.
//!
//! A fixed set of readings is taken as a **steady state**: the model observes them once, so
//! its history filters (if it has any) start at them and its history features are zero; the
//! spindle and the axes count as stopped (their heat-input features zero). That is the state of
//! a machine that has stood long enough at these temperatures. For a running machine, bring
//! the model to the state by letting it observe the readings' history instead (a warm-up
//! program run on the twin, or a controller's log) and sample it then.

use thiserror::Error;
use vmc_predict::predictor::ErrorPredictor;

/// Coldest reading accepted, °C.
pub const MIN_READING_DEGC: f64 = -50.0;
/// Warmest reading accepted, °C. Why these limits: a machine tool's structure lives between
/// shop temperatures and a warm spindle; beyond them a reading is a unit mistake (K, °F) or a
/// broken sensor.
pub const MAX_READING_DEGC: f64 = 150.0;

/// Problems with a set of readings.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum ReadingsError {
    /// Nothing given.
    #[error("no readings given (expected NAME=VALUE for each of {expected:?})")]
    Empty {
        /// The model's sensors.
        expected: Vec<String>,
    },
    /// An item that is not `NAME=VALUE`.
    #[error("reading {item:?} is not NAME=VALUE")]
    Malformed {
        /// The item.
        item: String,
    },
    /// A name the model does not have.
    #[error("unknown sensor `{name}` (the model reads {known:?})")]
    UnknownSensor {
        /// The name given.
        name: String,
        /// The model's sensors.
        known: Vec<String>,
    },
    /// A sensor given twice.
    #[error("sensor `{name}` is given twice")]
    Duplicate {
        /// The sensor.
        name: String,
    },
    /// Sensors of the model not given.
    #[error("no reading for {missing:?} (the model reads every one of {expected:?})")]
    Missing {
        /// The sensors without a reading.
        missing: Vec<String>,
        /// The model's sensors.
        expected: Vec<String>,
    },
    /// A value that is not a number.
    #[error("reading of `{name}`: {text:?} is not a number (°C)")]
    NotANumber {
        /// The sensor.
        name: String,
        /// The text.
        text: String,
    },
    /// A value outside the plausible range.
    #[error(
        "reading of `{name}`: {value_degc} °C is outside {min_degc} … {max_degc} °C (a unit \
         mistake or a broken sensor?)"
    )]
    Implausible {
        /// The sensor.
        name: String,
        /// The value, °C.
        value_degc: f64,
        /// Lowest accepted, °C.
        min_degc: f64,
        /// Highest accepted, °C.
        max_degc: f64,
    },
    /// A reading vector of the wrong length.
    #[error("{got} readings for a model of {expected} sensors")]
    WrongCount {
        /// The model's sensor count.
        expected: usize,
        /// Readings given.
        got: usize,
    },
}

/// The readings (°C, in `sensor_names` order) of `text`: `NAME=VALUE` items separated by
/// commas and/or white space, every sensor of the model exactly once, in any order.
///
/// # Errors
/// Nothing given, an item that is not `NAME=VALUE`, an unknown or repeated sensor, a missing
/// one, a value that is not a number or outside [`MIN_READING_DEGC`] … [`MAX_READING_DEGC`].
pub fn parse_readings(text: &str, sensor_names: &[String]) -> Result<Vec<f64>, ReadingsError> {
    let mut values: Vec<Option<f64>> = vec![None; sensor_names.len()];
    let items: Vec<&str> = text
        .split(|c: char| c == ',' || c.is_whitespace())
        .filter(|s| !s.is_empty())
        .collect();
    if items.is_empty() {
        return Err(ReadingsError::Empty {
            expected: sensor_names.to_vec(),
        });
    }
    for item in items {
        let (name, value) = item
            .split_once('=')
            .ok_or_else(|| ReadingsError::Malformed { item: item.into() })?;
        let i = sensor_names.iter().position(|s| s == name).ok_or_else(|| {
            ReadingsError::UnknownSensor {
                name: name.into(),
                known: sensor_names.to_vec(),
            }
        })?;
        if values[i].is_some() {
            return Err(ReadingsError::Duplicate { name: name.into() });
        }
        values[i] = Some(read_value(name, value)?);
    }
    let missing: Vec<String> = sensor_names
        .iter()
        .zip(&values)
        .filter(|(_, v)| v.is_none())
        .map(|(n, _)| n.clone())
        .collect();
    if !missing.is_empty() {
        return Err(ReadingsError::Missing {
            missing,
            expected: sensor_names.to_vec(),
        });
    }
    Ok(values.into_iter().flatten().collect())
}

fn read_value(name: &str, text: &str) -> Result<f64, ReadingsError> {
    let v: f64 = text.parse().map_err(|_| ReadingsError::NotANumber {
        name: name.into(),
        text: text.into(),
    })?;
    if (MIN_READING_DEGC..=MAX_READING_DEGC).contains(&v) {
        Ok(v)
    } else {
        Err(ReadingsError::Implausible {
            name: name.into(),
            value_degc: v,
            min_degc: MIN_READING_DEGC,
            max_degc: MAX_READING_DEGC,
        })
    }
}

/// Brings `model` to the steady state of `readings_degc` (°C, the model's sensor order; see the
/// module doc): one observation at time 0, the spindle and the axes stopped.
///
/// # Errors
/// [`ReadingsError::WrongCount`] when the readings do not match the model's sensors.
pub fn observe_steady_state<P: ErrorPredictor + ?Sized>(
    model: &mut P,
    readings_degc: &[f64],
) -> Result<(), ReadingsError> {
    let expected = model.sensor_names().len();
    if readings_degc.len() != expected {
        return Err(ReadingsError::WrongCount {
            expected,
            got: readings_degc.len(),
        });
    }
    model.observe_readings(0.0, readings_degc);
    model.observe_spindle_speed(0.0, 0.0);
    model.observe_axis_feeds(0.0, [0.0; 3]);
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testmodel::Analytic;

    fn names() -> Vec<String> {
        ["BXH", "ZT", "Amb"].iter().map(|s| s.to_string()).collect()
    }

    #[test]
    fn readings_are_read_in_the_models_order_whatever_their_order() {
        let v = parse_readings("Amb=20.5, BXH=24.1 ZT=26", &names()).unwrap();
        assert_eq!(v, [24.1, 26.0, 20.5]);
    }

    #[test]
    fn unknown_repeated_missing_and_implausible_readings_are_refused() {
        let n = names();
        assert!(matches!(
            parse_readings("BXH=24,ZT=25,Amb=20,XX=1", &n).unwrap_err(),
            ReadingsError::UnknownSensor { .. }
        ));
        assert_eq!(
            parse_readings("BXH=24,BXH=25", &n).unwrap_err(),
            ReadingsError::Duplicate { name: "BXH".into() }
        );
        assert_eq!(
            parse_readings("BXH=24", &n).unwrap_err(),
            ReadingsError::Missing {
                missing: vec!["ZT".into(), "Amb".into()],
                expected: n.clone()
            }
        );
        assert!(matches!(
            parse_readings("BXH=297.1,ZT=25,Amb=20", &n).unwrap_err(),
            ReadingsError::Implausible { .. }
        ));
        assert!(matches!(
            parse_readings("BXH=warm,ZT=25,Amb=20", &n).unwrap_err(),
            ReadingsError::NotANumber { .. }
        ));
        assert!(matches!(
            parse_readings("BXH 24", &n).unwrap_err(),
            ReadingsError::Malformed { .. }
        ));
        assert!(matches!(
            parse_readings(" , ", &n).unwrap_err(),
            ReadingsError::Empty { .. }
        ));
    }

    #[test]
    fn a_steady_state_is_observed_once_and_a_wrong_count_is_refused() {
        let mut m = Analytic::new();
        assert_eq!(
            observe_steady_state(&mut m, &[20.0, 21.0]).unwrap_err(),
            ReadingsError::WrongCount {
                expected: 1,
                got: 2
            }
        );
        observe_steady_state(&mut m, &[23.0]).unwrap();
        let q = [100.0, 100.0, -100.0];
        assert_eq!(m.predict_error_mm(q), Analytic::error_mm(q, 23.0));
    }
}
