//! A synthetic machine for the examples and tests: smooth motion errors of three axes with a
//! thermal expansion term, a reversal per axis, a spindle drift and squareness, sampled like
//! alternating bidirectional laser sweeps over three thermal cycles, and a hybrid model trained
//! on them, returned as the application gets it (written to model-file text and read back) at
//! a steady thermal state. Its truth is not the twin's: it only has to give a real trained
//! model with a reversal.

use vmc_predict::dataset::{Dataset, Instrument, Record};
use vmc_predict::predictor::{train_hybrid, AnyPredictor, ErrorPredictor, Settings};
use vmc_predict::synthesis::{Chain, MachineGeometry};
use vmc_tables::readings::{observe_steady_state, parse_readings};
use vmc_tables::sample::{AxisTravel, SamplingSpec};

pub const SENSORS: [&str; 3] = ["S1", "S2", "Amb"];
pub const TRAVEL_MM: [[f64; 2]; 3] = [[0.0, 560.0], [0.0, 400.0], [-450.0, 0.0]];
/// Positioning error of a positive approach minus a negative one, µm, per axis.
pub const REVERSAL_UM: [f64; 3] = [0.8, 0.6, 1.0];

/// A deterministic noise of ±0.05 µm (an LCG: the test needs no random generator).
struct Noise(u64);

impl Noise {
    fn next_um(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((self.0 >> 11) as f64 / (1u64 << 53) as f64 - 0.5) * 0.1
    }
}

fn temps_degc(amp: f64, t_s: f64) -> Vec<f64> {
    let rise = |tau: f64| 1.0 - (-t_s / tau).exp();
    vec![
        20.0 + amp * rise(1800.0),
        20.0 + 0.6 * amp * rise(4000.0),
        20.0 + 0.3 * (t_s / 7200.0).sin(),
    ]
}

/// Motion errors of axis `k` at `s_mm`: dx, dy, dz (µm), rx, ry, rz (µrad).
fn axis_errors(k: usize, s_mm: f64, t: &[f64]) -> [f64; 6] {
    let [lo, hi] = TRAVEL_MM[k];
    let s = (s_mm - lo) / (hi - lo);
    let d = t[0] - 20.0;
    let mut v = [
        3.0 * s * s,
        2.0 * (3.0 * s).sin(),
        1.5 * s * (1.0 - s),
        2.0 * s - 1.0,
        1.5 * (2.0 * s).cos(),
        -s,
    ];
    v[k] += 0.011 * (s_mm - lo) * d;
    v
}

fn dataset() -> Dataset {
    let mut noise = Noise(7);
    let mut records = Vec::new();
    for (c, amp) in [4.0, 7.0, 5.5].into_iter().enumerate() {
        for step in 0..=12 {
            let time_s = step as f64 * 1200.0;
            let temps = temps_degc(amp, time_s);
            // Successive blocks sweep forward and backward (alternating bidirectional runs).
            let dir: i8 = if step % 2 == 0 { 1 } else { -1 };
            let rec = |instrument, pos_mm, values, dir| Record {
                cycle: format!("c{c}"),
                time_s,
                instrument,
                pos_mm,
                values,
                temps_degc: temps.clone(),
                dir,
                spindle_rpm: None,
                axis_feed_mm_per_min: None,
            };
            for k in 0..3 {
                let [lo, hi] = TRAVEL_MM[k];
                for i in 0..=10 {
                    let mut pos = [280.0, 200.0, -225.0];
                    pos[k] = lo + (hi - lo) * i as f64 / 10.0;
                    let mut v = axis_errors(k, pos[k], &temps);
                    v[k] += 0.5 * REVERSAL_UM[k] * f64::from(dir);
                    let v = v.map(|x| x + noise.next_um());
                    records.push(rec(Instrument::laser(k), pos, v, dir));
                }
            }
            let d = temps[0] - 20.0;
            let sp = [0.3 * d, 0.2 * d, -2.5 * d, 0.4 * d, -0.3 * d, f64::NAN];
            records.push(rec(Instrument::Spindle, [280.0, 200.0, -225.0], sp, 1));
            let sq = [f64::NAN, f64::NAN, f64::NAN, 5.0, -8.0 + 0.3 * d, 12.0];
            records.push(rec(Instrument::Squareness, [280.0, 200.0, -225.0], sq, 1));
        }
    }
    Dataset {
        sensor_names: SENSORS.map(String::from).to_vec(),
        records,
        origin: None,
    }
}

/// The model as the application gets it: trained, written to its file text, read back.
pub fn model_at_state() -> AnyPredictor {
    let geometry = MachineGeometry {
        chain: Chain::parse("w X Y b Z t").unwrap(),
        tool_offset_mm: [0.0, 0.0, -150.0],
    };
    let settings = Settings {
        hidden_candidates: vec![6],
        max_epochs: 15,
        ..Settings::default()
    };
    let (trained, _) = train_hybrid(&dataset(), &geometry, &settings).unwrap();
    let text = AnyPredictor::Hybrid(trained).to_json_string().unwrap();
    let mut model = AnyPredictor::from_json_str(&text).unwrap();
    let readings = parse_readings("S1=25.5 S2=23.1 Amb=20.4", model.sensor_names()).unwrap();
    observe_steady_state(&mut model, &readings).unwrap();
    model
}

/// The default sampling of the synthetic machine's travels.
pub fn spec() -> SamplingSpec {
    SamplingSpec::new(TRAVEL_MM.map(|[min_mm, max_mm]| AxisTravel { min_mm, max_mm }))
}
