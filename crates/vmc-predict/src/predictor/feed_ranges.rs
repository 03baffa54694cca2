//! The trained ranges of the axes' filtered commanded feeds (what the extrapolation guard checks
//! a model with feed inputs against).

use crate::dataset::Dataset;
use crate::history::FeedHistory;
use crate::provenance::FeedRanges;

use super::data::for_each_feed_instant;

/// The ranges of the feed filters `taus_s` over `data`, through the same filtering as the
/// model's training. None without time constants or when a record lacks the feeds.
pub fn feed_ranges(data: &Dataset, taus_s: &[f64]) -> Option<FeedRanges> {
    if taus_s.is_empty()
        || data
            .records
            .iter()
            .any(|r| r.axis_feed_mm_per_min.is_none())
    {
        return None;
    }
    let mut ranges =
        vec![[f64::INFINITY, f64::NEG_INFINITY]; FeedHistory::n_features(taus_s.len())];
    for_each_feed_instant(data, taus_s, |_, _, f| {
        for (range, v) in ranges.iter_mut().zip(f) {
            range[0] = range[0].min(*v);
            range[1] = range[1].max(*v);
        }
    });
    Some(FeedRanges {
        taus_s: taus_s.to_vec(),
        filtered_m_per_min: ranges,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dataset::{Instrument, Record};

    fn record(cycle: &str, time_s: f64, feed: Option<[f64; 3]>) -> Record {
        Record {
            cycle: cycle.into(),
            time_s,
            instrument: Instrument::Spindle,
            pos_mm: [0.0; 3],
            values: [0.0; 6],
            temps_degc: vec![20.0],
            dir: 1,
            spindle_rpm: None,
            axis_feed_mm_per_min: feed,
        }
    }

    #[test]
    fn feed_ranges_follow_each_cycle_through_the_models_filters() {
        // Cycle a: X at 6 m/min for 10 τ; cycle b (filters restart at rest): Z at 2 m/min.
        let mut records = Vec::new();
        for k in 0..=100 {
            let t = f64::from(k) * 60.0;
            records.push(record(
                "a",
                t,
                Some([if k == 0 { 0.0 } else { 6000.0 }, 0.0, 0.0]),
            ));
            records.push(record(
                "b",
                t,
                Some([0.0, 0.0, if k == 0 { 0.0 } else { 2000.0 }]),
            ));
        }
        let data = Dataset {
            sensor_names: vec!["s".into()],
            records,
            ..Default::default()
        };
        let r = feed_ranges(&data, &[600.0]).unwrap();
        assert_eq!(r.taus_s, vec![600.0]);
        let [x, y, z] = [
            r.filtered_m_per_min[0],
            r.filtered_m_per_min[1],
            r.filtered_m_per_min[2],
        ];
        // 6000 s = 10 τ: the filter reaches the feed within e^-10.
        assert_eq!(x[0], 0.0);
        assert!((x[1] - 6.0).abs() < 6.0 * 1e-4, "{x:?}");
        assert_eq!(y, [0.0, 0.0]);
        assert!((z[1] - 2.0).abs() < 2.0 * 1e-4, "{z:?}");
        assert_eq!(r.name(2), "z_feed_600s");
        // No filters, or a record without feeds: nothing to record.
        assert_eq!(feed_ranges(&data, &[]), None);
        let mut missing = data.clone();
        missing.records[7].axis_feed_mm_per_min = None;
        assert_eq!(feed_ranges(&missing, &[600.0]), None);
    }
}
