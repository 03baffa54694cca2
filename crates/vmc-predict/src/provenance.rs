//! What a model was trained on, and the guard that says when it is used outside it.
//!
//! A model records ([`TrainedOn`], the model file's `trained_on` object, version 8):
//! - the identity of the machine it was calibrated on ([`MachineIdentity`]: name, realisation
//!   and a fingerprint of the machine description), so that a model of another machine or of
//!   another realisation of the same design is not used without a word;
//! - the range of every input it was trained on ([`InputRanges`]: each sensor's readings and,
//!   when the dataset logs it, the commanded spindle speed).
//!
//! [`Guarded`] wraps the loop's controller: every reading and every commanded spindle speed is
//! compared with the ranges, with a small margin ([`InputRanges::margin_degc`],
//! [`InputRanges::margin_rpm`]); what lies outside is counted ([`Extrapolation`]). A model used
//! there extrapolates: it may be right, but nothing it learnt says so.

use serde::{Deserialize, Serialize};

use crate::controller::Controller;
use crate::dataset::Dataset;

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

    /// The ranges of `sensors` (names of `data`'s columns) and of the logged spindle speed over
    /// every record of `data`. A sensor without a finite reading gets `[NaN, NaN]`, never
    /// outside.
    pub fn of(data: &Dataset, sensors: &[String]) -> Self {
        let cols: Vec<Option<usize>> = sensors
            .iter()
            .map(|n| data.sensor_names.iter().position(|d| d == n))
            .collect();
        let mut sensor_degc = vec![[f64::INFINITY, f64::NEG_INFINITY]; sensors.len()];
        let mut rpm: Option<[f64; 2]> = None;
        for r in &data.records {
            for (range, col) in sensor_degc.iter_mut().zip(&cols) {
                if let Some(v) = col
                    .and_then(|c| r.temps_degc.get(c))
                    .filter(|v| v.is_finite())
                {
                    range[0] = range[0].min(*v);
                    range[1] = range[1].max(*v);
                }
            }
            if let Some(n) = r.spindle_rpm.filter(|n| n.is_finite()) {
                let range = rpm.get_or_insert([n, n]);
                range[0] = range[0].min(n);
                range[1] = range[1].max(n);
            }
        }
        for range in &mut sensor_degc {
            if range[0] > range[1] {
                *range = [f64::NAN, f64::NAN];
            }
        }
        InputRanges {
            sensors: sensors.to_vec(),
            sensor_degc,
            spindle_rpm: rpm,
        }
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
    /// The input: a sensor name or `spindle_rpm`.
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
    fn note(&mut self, input: &str, range: [f64; 2], value: f64, time_s: f64) {
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

fn outside(range: [f64; 2], v: f64, margin: f64) -> bool {
    // NaN ranges (an input the training never saw a value of) and NaN readings compare false.
    v < range[0] - margin || v > range[1] + margin
}

/// A controller whose inputs are checked against a model's trained ranges on their way in.
#[derive(Debug, Clone)]
pub struct Guarded<C> {
    inner: C,
    /// For each machine sensor (reading order), the model input's range, if the model has it.
    ranges: Vec<Option<(String, [f64; 2])>>,
    rpm: Option<[f64; 2]>,
    seen: Extrapolation,
}

impl<C: Controller> Guarded<C> {
    /// Wraps `inner`, checking the readings of `machine_sensors` (reading order) and the
    /// commanded spindle speed against `ranges`.
    pub fn new(inner: C, trained: &InputRanges, machine_sensors: &[String]) -> Self {
        let ranges = machine_sensors
            .iter()
            .map(|n| {
                trained
                    .sensors
                    .iter()
                    .position(|m| m == n)
                    .and_then(|i| trained.sensor_degc.get(i))
                    .map(|r| (n.clone(), *r))
            })
            .collect();
        Guarded {
            inner,
            ranges,
            rpm: trained.spindle_rpm,
            seen: Extrapolation::default(),
        }
    }

    /// What was outside so far.
    pub fn extrapolation(&self) -> &Extrapolation {
        &self.seen
    }

    /// The wrapped controller.
    pub fn inner(&self) -> &C {
        &self.inner
    }
}

impl<C: Controller> Controller for Guarded<C> {
    fn on_readings(&mut self, time_s: f64, values_degc: &[f64]) {
        for (r, v) in self.ranges.iter().zip(values_degc) {
            if let Some((name, range)) = r {
                self.seen.samples += 1;
                if outside(*range, *v, InputRanges::margin_degc()) {
                    self.seen.note(name, *range, *v, time_s);
                }
            }
        }
        self.inner.on_readings(time_s, values_degc);
    }

    fn on_spindle_speed(&mut self, time_s: f64, rpm: f64) {
        if let Some(range) = self.rpm {
            self.seen.samples += 1;
            if outside(range, rpm, InputRanges::margin_rpm()) {
                self.seen.note("spindle_rpm", range, rpm, time_s);
            }
        }
        self.inner.on_spindle_speed(time_s, rpm);
    }

    fn on_axis_feeds(&mut self, time_s: f64, feeds_mm_per_min: [f64; 3]) {
        self.inner.on_axis_feeds(time_s, feeds_mm_per_min);
    }

    fn on_commanded_motion(&mut self, start_mm: [f64; 3], end_mm: [f64; 3]) {
        self.inner.on_commanded_motion(start_mm, end_mm);
    }

    #[inline]
    fn axis_command_mm(&mut self, p_mm: [f64; 3]) -> [f64; 3] {
        self.inner.axis_command_mm(p_mm)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    struct Null;
    impl Controller for Null {
        fn axis_command_mm(&mut self, p_mm: [f64; 3]) -> [f64; 3] {
            p_mm
        }
    }

    fn ranges() -> InputRanges {
        InputRanges {
            sensors: vec!["A".into(), "B".into()],
            sensor_degc: vec![[19.0, 30.0], [18.0, 22.0]],
            spindle_rpm: Some([0.0, 9000.0]),
        }
    }

    #[test]
    fn the_guard_is_silent_inside_the_trained_ranges() {
        let names = vec!["B".to_string(), "A".to_string(), "C".to_string()];
        let mut g = Guarded::new(Null, &ranges(), &names);
        for k in 0..100 {
            let t = f64::from(k);
            // C is not a model input: never checked.
            g.on_readings(t, &[18.0 + 0.04 * t, 30.0 - 0.1 * t, 99.0]);
            g.on_spindle_speed(t, 90.0 * t);
        }
        let e = g.extrapolation();
        assert_eq!(e.samples, 300);
        assert_eq!((e.count, e.first_time_s), (0, None));
        assert!(e.inputs.is_empty());
    }

    #[test]
    fn the_guard_reports_a_reading_and_a_speed_outside_the_trained_ranges() {
        let names = vec!["A".to_string(), "B".to_string()];
        let mut g = Guarded::new(Null, &ranges(), &names);
        g.on_readings(1.0, &[25.0, 20.0]);
        g.on_spindle_speed(1.0, 9000.5);
        // B 0.3 °C above its range: outside (margin 0.2 °C).
        g.on_readings(2.0, &[25.0, 22.3]);
        g.on_readings(3.0, &[25.0, 22.5]);
        g.on_spindle_speed(3.0, 12000.0);
        let e = g.extrapolation();
        assert_eq!(e.count, 3);
        assert_eq!(e.first_time_s, Some(2.0));
        assert_eq!(e.inputs.len(), 2);
        assert_eq!(e.inputs[0].input, "B");
        assert_eq!((e.inputs[0].count, e.inputs[0].first_value), (2, 22.3));
        assert_eq!(e.inputs[1].input, "spindle_rpm");
        assert_eq!(e.inputs[1].first_time_s, 3.0);
    }

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
