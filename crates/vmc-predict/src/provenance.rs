//! What a model was trained on, and the guard that says when it is used outside it.
//!
//! A model records ([`TrainedOn`], the model file's `trained_on` object, version 8):
//! - the identity of the machine it was calibrated on ([`MachineIdentity`]: name, realisation
//!   and a fingerprint of the machine description), so that a model of another machine or of
//!   another realisation of the same design is not used without a word;
//! - the range of every input it was trained on ([`InputRanges`]: each sensor's readings, when
//!   the dataset logs it the commanded spindle speed, and for a model that reads the axes'
//!   commanded feeds the range of each filtered feed it was trained on, [`FeedRanges`]).
//!
//! The guard module's `Guarded` wraps the loop's controller and counts what lies outside the
//! ranges ([`Extrapolation`]).

use serde::{Deserialize, Serialize};

/// The machine a model was calibrated on.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct MachineIdentity {
    /// The machine's name (its description's `machine.name`).
    pub name: String,
    /// The realisation: the twin's machine seed, or a machine's serial number (None: unknown).
    pub realisation: Option<u64>,
    /// A fingerprint of the machine description (hex), see the application's `fingerprint`.
    pub fingerprint: String,
}

impl MachineIdentity {
    /// The way `other` differs from this one (None: the same machine). A realisation recorded
    /// on one side only is not a difference.
    pub fn difference(&self, other: &MachineIdentity) -> Option<String> {
        if self.name != other.name {
            return Some(format!(
                "it was calibrated on machine `{}`, this is `{}`",
                self.name, other.name
            ));
        }
        if self.fingerprint != other.fingerprint {
            return Some(format!(
                "it was calibrated on a machine `{}` described differently (fingerprint {} \
                 against {})",
                self.name, self.fingerprint, other.fingerprint
            ));
        }
        match (self.realisation, other.realisation) {
            (Some(a), Some(b)) if a != b => Some(format!(
                "it was calibrated on realisation {a} of machine `{}`, this is realisation {b}",
                self.name
            )),
            _ => None,
        }
    }
}

/// The range of every model input over the training data.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct InputRanges {
    /// Sensor names, in the model's input order.
    pub sensors: Vec<String>,
    /// `[min, max]` of each sensor's readings, °C.
    pub sensor_degc: Vec<[f64; 2]>,
    /// `[min, max]` of the commanded spindle speed, rpm (None: not logged).
    pub spindle_rpm: Option<[f64; 2]>,
    /// The axes' filtered commanded feeds the model reads, and their ranges (None: the model
    /// does not read them, or a file written before they were recorded).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub axis_feeds: Option<FeedRanges>,
}

/// The trained range of the axes' commanded-feed inputs: each axis's mean |speed| through each
/// low-pass filter of the model (the inputs themselves, not the instantaneous feed: a test's
/// rapid moves exceed every logged mean for seconds without moving an hour-long filter).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FeedRanges {
    /// The filters' time constants, s.
    pub taus_s: Vec<f64>,
    /// `[min, max]` of each filtered feed over the training records, m/min: X's per time
    /// constant, then Y's, then Z's.
    pub filtered_m_per_min: Vec<[f64; 2]>,
}

impl FeedRanges {
    /// The name of feature `k` in reports, e.g. `z_feed_3600s`.
    pub fn name(&self, k: usize) -> String {
        let per_axis = self.taus_s.len().max(1);
        let axis = ["x", "y", "z"].get(k / per_axis).copied().unwrap_or("?");
        let tau = self.taus_s.get(k % per_axis).copied().unwrap_or(f64::NAN);
        format!("{axis}_feed_{tau}s")
    }
}

impl InputRanges {
    /// A reading counts as outside when it is more than this beyond the range, °C (a little
    /// above a sensor's noise and resolution).
    pub const fn margin_degc() -> f64 {
        0.2
    }

    /// A commanded speed counts as outside when it is more than this above the range, rpm.
    pub const fn margin_rpm() -> f64 {
        1.0
    }

    /// A filtered feed counts as outside when it is more than this beyond its range, m/min.
    pub const fn margin_m_per_min() -> f64 {
        0.05
    }
}

/// What a model file records of its training (the `trained_on` object).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TrainedOn {
    /// The machine the calibration ran on (None: not recorded).
    pub machine: Option<MachineIdentity>,
    /// The inputs' ranges.
    pub inputs: InputRanges,
}

/// One input found outside its trained range.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct OutsideInput {
    /// The input: a sensor name, `spindle_rpm` or a filtered feed (`z_feed_3600s`).
    pub input: String,
    /// Its trained range.
    pub range: [f64; 2],
    /// The first value outside.
    pub first_value: f64,
    /// When, s.
    pub first_time_s: f64,
    /// How many samples of this input were outside.
    pub count: u64,
}

/// What the guard saw: inputs outside the trained ranges.
#[derive(Debug, Clone, PartialEq, Default, Serialize)]
pub struct Extrapolation {
    /// Samples checked (readings and speeds).
    pub samples: u64,
    /// The first time any input was outside, s (None: never).
    pub first_time_s: Option<f64>,
    /// Samples outside, all inputs together.
    pub count: u64,
    /// Per input that was outside at least once, in the order first met.
    pub inputs: Vec<OutsideInput>,
}

impl Extrapolation {
    pub(crate) fn note(&mut self, input: &str, range: [f64; 2], value: f64, time_s: f64) {
        self.count += 1;
        self.first_time_s.get_or_insert(time_s);
        match self.inputs.iter_mut().find(|o| o.input == input) {
            Some(o) => o.count += 1,
            None => self.inputs.push(OutsideInput {
                input: input.to_string(),
                range,
                first_value: value,
                first_time_s: time_s,
                count: 1,
            }),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn identities_differ_by_name_fingerprint_or_realisation() {
        let a = MachineIdentity {
            name: "m".into(),
            realisation: Some(1),
            fingerprint: "f".into(),
        };
        assert_eq!(a.difference(&a), None);
        let unknown = MachineIdentity {
            realisation: None,
            ..a.clone()
        };
        assert_eq!(a.difference(&unknown), None);
        let other = MachineIdentity {
            realisation: Some(2),
            ..a.clone()
        };
        assert!(a.difference(&other).unwrap().contains("realisation 1"));
        let renamed = MachineIdentity {
            name: "n".into(),
            ..a.clone()
        };
        assert!(a.difference(&renamed).unwrap().contains("`n`"));
        let changed = MachineIdentity {
            fingerprint: "g".into(),
            ..a.clone()
        };
        assert!(a.difference(&changed).unwrap().contains("fingerprint"));
    }
}
