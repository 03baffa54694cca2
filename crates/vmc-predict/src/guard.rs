//! The extrapolation guard: a controller whose inputs are checked against a model's trained
//! ranges on their way in.
//!
//! Every reading, every commanded spindle speed and, for a model that reads them, the axes'
//! filtered commanded feeds are compared with the ranges, with a small margin
//! ([`InputRanges::margin_degc`], [`InputRanges::margin_rpm`],
//! [`InputRanges::margin_m_per_min`]); what lies outside is counted ([`Extrapolation`]). A model used there extrapolates: it may be right, but nothing it
//! learnt says so.

use crate::controller::Controller;
use crate::history::FeedHistory;
use crate::provenance::{Extrapolation, FeedRanges, InputRanges};

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
    /// The model's feed filters, fed what the controller commanded, and their trained ranges.
    feeds: Option<(FeedHistory, FeedRanges, Vec<f64>)>,
    seen: Extrapolation,
}

impl<C: Controller> Guarded<C> {
    /// Wraps `inner`, checking the readings of `machine_sensors` (reading order), the
    /// commanded spindle speed and the filtered commanded feeds against `ranges`.
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
            feeds: trained.axis_feeds.as_ref().map(|r| {
                let h = FeedHistory::new(&r.taus_s);
                let n = h.len();
                (h, r.clone(), vec![0.0; n])
            }),
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

    /// The wrapped controller, to update what it knows between moves (a probed drift); what
    /// it is fed through [`Controller`] stays guarded.
    pub fn inner_mut(&mut self) -> &mut C {
        &mut self.inner
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
        if let Some((h, ranges, f)) = &mut self.feeds {
            h.observe(time_s, feeds_mm_per_min);
            h.features_into(f);
            for (k, (range, v)) in ranges.filtered_m_per_min.iter().zip(f.iter()).enumerate() {
                self.seen.samples += 1;
                if outside(*range, *v, InputRanges::margin_m_per_min()) {
                    self.seen.note(&ranges.name(k), *range, *v, time_s);
                }
            }
        }
        self.inner.on_axis_feeds(time_s, feeds_mm_per_min);
    }

    fn on_commanded_motion(&mut self, start_mm: [f64; 3], end_mm: [f64; 3]) {
        self.inner.on_commanded_motion(start_mm, end_mm);
    }

    fn on_tool_change(&mut self, tool_offset_mm: [f64; 3]) -> Result<(), String> {
        self.inner.on_tool_change(tool_offset_mm)
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
        fn on_readings(&mut self, _time_s: f64, _values_degc: &[f64]) {}
        fn on_spindle_speed(&mut self, _time_s: f64, _rpm: f64) {}
        fn on_axis_feeds(&mut self, _time_s: f64, _feeds_mm_per_min: [f64; 3]) {}
        fn axis_command_mm(&mut self, p_mm: [f64; 3]) -> [f64; 3] {
            p_mm
        }
    }

    fn ranges() -> InputRanges {
        InputRanges {
            sensors: vec!["A".into(), "B".into()],
            sensor_degc: vec![[19.0, 30.0], [18.0, 22.0]],
            spindle_rpm: Some([0.0, 9000.0]),
            axis_feeds: None,
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

    /// Trained ranges with X and Y filtered feeds up to 4 m/min and Z up to 10 m/min (τ = 600 s).
    fn feed_ranges() -> InputRanges {
        InputRanges {
            axis_feeds: Some(FeedRanges {
                taus_s: vec![600.0],
                filtered_m_per_min: vec![[0.0, 4.0], [0.0, 4.0], [0.0, 10.0]],
            }),
            ..ranges()
        }
    }

    #[test]
    fn the_guard_follows_the_filtered_feeds_not_the_moments_rapids() {
        let names = vec!["A".to_string(), "B".to_string()];
        let mut g = Guarded::new(Null, &feed_ranges(), &names);
        // An hour at 3 m/min on every axis, with a 30 m/min rapid of 2 s every minute: the
        // filter (τ = 10 min) stays near 3.9 m/min, inside every range.
        g.on_axis_feeds(0.0, [0.0; 3]);
        for k in 1..=3600 {
            let f = if k % 60 < 2 { 30_000.0 } else { 3000.0 };
            g.on_axis_feeds(f64::from(k), [f; 3]);
        }
        assert_eq!(g.extrapolation().samples, 3 * 3601);
        assert!(
            g.extrapolation().inputs.is_empty(),
            "{:?}",
            g.extrapolation()
        );
        // Then Z alone at 12 m/min: from about 3.9 m/min (the hour's mean feed) its filter
        // passes 10.05 m/min after 600 s × ln(8.1 / 1.95) ≈ 854 s.
        for k in 3601..=7200 {
            g.on_axis_feeds(f64::from(k), [0.0, 0.0, 12_000.0]);
        }
        let e = g.extrapolation();
        assert_eq!(e.inputs.len(), 1, "{e:?}");
        assert_eq!(e.inputs[0].input, "z_feed_600s");
        assert_eq!(e.inputs[0].range, [0.0, 10.0]);
        let first = e.inputs[0].first_time_s - 3600.0;
        assert!((first - 854.0).abs() < 15.0, "{first}");
        assert!(e.inputs[0].first_value > 10.05 && e.inputs[0].first_value < 10.1);
    }
}
