//! Synthetic calibration data for the integration tests and benches of the compiled model: a
//! smooth ground truth of position, temperatures and the commanded spindle speed (not the twin),
//! sampled as the instruments would, with noise, for a model shaped like the reference
//! machine's: its 12 sensor names, the ambient sensor's history feature, the spindle nose's
//! rate for the spindle part, the axes' feed filters, bidirectional laser sweeps.
//!
//! Units: mm, µm, µrad, °C, s, rpm, mm/min.
#![allow(dead_code)] // each test binary uses a part of it

use std::f64::consts::PI;

use rand::rngs::StdRng;
use rand::{RngExt, SeedableRng};
use rand_distr::{Distribution, Normal};
use vmc_predict::dataset::{Dataset, Instrument, Record};
use vmc_predict::predictor::{train_hybrid, HybridPredictor, Settings};
use vmc_predict::synthesis::{Chain, MachineGeometry};

/// The reference machine's sensor names (the knowledge side knows names, nothing else).
pub const SENSORS: [&str; 12] = [
    "BXH", "BYH", "BXB", "BYB", "XD", "XG", "YAv", "YAr", "ZH", "ZB", "ZT", "Amb",
];
/// Axis travels, mm (min, max).
pub const TRAVEL_MM: [(f64, f64); 3] = [(0.0, 560.0), (0.0, 400.0), (-450.0, 0.0)];
/// Heating phase of a cycle, s.
const HEAT_S: f64 = 3.0 * 3600.0;

/// A vertical machine: X table on Y saddle, Z head, 150 mm tool.
pub fn geometry() -> MachineGeometry {
    MachineGeometry {
        chain: Chain::parse("w X Y b Z t").expect("a valid chain"),
        tool_offset_mm: [0.0, 0.0, -150.0],
    }
}

/// Readings (°C) at `t_s` of a cycle of heating amplitude `amp_degc`: each sensor rises with its
/// own time constant while heating (3 h) and falls after; the ambient swings over 4 h.
pub fn temps_degc(amp_degc: f64, t_s: f64) -> Vec<f64> {
    (0..SENSORS.len())
        .map(|i| {
            if i == SENSORS.len() - 1 {
                return 20.0 + 0.6 * (2.0 * PI * t_s / 14_400.0 + amp_degc).sin();
            }
            let tau = 900.0 + 350.0 * i as f64;
            let gain = 1.0 - 0.06 * i as f64;
            let rise = |t: f64| 1.0 - (-t / tau).exp();
            let d = if t_s <= HEAT_S {
                rise(t_s)
            } else {
                rise(HEAT_S) * (-(t_s - HEAT_S) / tau).exp()
            };
            20.0 + amp_degc * gain * d
        })
        .collect()
}

/// Commanded spindle speed (rpm) and axis feeds (mm/min) of a cycle at `t_s`.
pub fn commands(amp_degc: f64, t_s: f64) -> (f64, [f64; 3]) {
    if t_s <= HEAT_S {
        (1000.0 * amp_degc, [2500.0, 1800.0, 600.0])
    } else {
        (0.0, [0.0; 3])
    }
}

/// True motion errors of axis `k` at `s_mm`: δ (µm) then ε (µrad).
fn axis_truth(k: usize, s_mm: f64, temps: &[f64]) -> [f64; 6] {
    let (lo, hi) = TRAVEL_MM[k];
    let s = (s_mm - lo) / (hi - lo);
    let dt = |i: usize| temps[i] - 20.0;
    let shapes = [
        s * s,
        (PI * s).sin(),
        s * (1.0 - s),
        (2.0 * s).cos(),
        s - 0.5,
        -s * s,
    ];
    std::array::from_fn(|j| {
        let amp = 2.0 + ((k * 6 + j) % 4) as f64;
        let th = 0.5 * dt((j + 4 * k) % 11) + 0.3 * dt((j + 1) % 11);
        let scale = if j == k {
            0.011 * (s_mm - lo) * dt(4 + 2 * k)
        } else {
            0.0
        };
        amp * shapes[j] + 0.2 * th * (1.0 + s) * (1.0 + 0.5 * (3.0 * s).sin()) + scale
    })
}

/// True spindle drifts: δx, δy, δz (µm), εx, εy (µrad).
fn spindle_truth(temps: &[f64]) -> [f64; 5] {
    let d = |i: usize| temps[i] - 20.0;
    [
        0.3 * d(0) - 0.1 * d(2),
        0.5 * d(1) + 0.04 * d(0) * d(0),
        -(3.0 * d(2) + 1.5 * d(3)) + 0.1 * d(2) * d(3),
        0.4 * d(1),
        -0.3 * d(0) + 0.2 * d(3),
    ]
}

/// True squareness α_yz, α_xz, α_xy (µrad).
fn squareness_truth(temps: &[f64]) -> [f64; 3] {
    let d = |i: usize| temps[i] - 20.0;
    [5.0 + 0.3 * d(8), -8.0 + 0.5 * d(9), 12.0 - 0.2 * d(6)]
}

/// A calibration dataset of cycles of heating amplitudes `amps_degc`: a measurement round
/// every 20 min over 4 h (laser sweeps of the three axes, backward on odd rounds with a
/// reversal, the spindle test, the squareness), noise 0.1 µm/µrad (laser), 0.2 (spindle,
/// squareness), 0.02 °C (sensors).
pub fn dataset(amps_degc: &[f64], seed: u64) -> Dataset {
    let mut rng = StdRng::seed_from_u64(seed);
    let mut noise = |sigma: f64| Normal::new(0.0, sigma).map_or(0.0, |n| n.sample(&mut rng));
    let reversal_um = [-0.5, -0.6, 0.4];
    let mut records = Vec::new();
    for (c, &amp) in amps_degc.iter().enumerate() {
        for round in 0..=12 {
            let t_s = f64::from(round) * 1200.0;
            let truth_t = temps_degc(amp, t_s);
            let (rpm, feeds) = commands(amp, (t_s - 600.0).max(0.0));
            let mut push =
                |instrument, pos_mm, values: [f64; 6], dir, noise: &mut dyn FnMut(f64) -> f64| {
                    records.push(Record {
                        cycle: format!("cycle{c}"),
                        time_s: t_s,
                        instrument,
                        pos_mm,
                        values,
                        temps_degc: truth_t.iter().map(|t| t + noise(0.02)).collect(),
                        dir,
                        spindle_rpm: Some(rpm),
                        axis_feed_mm_per_min: Some(feeds),
                    });
                };
            let backward = round % 2 == 1;
            for k in 0..3 {
                let (lo, hi) = TRAVEL_MM[k];
                for i in 0..=10 {
                    let mut pos = [0.0, 0.0, -100.0];
                    pos[k] = lo + (hi - lo) * f64::from(i) / 10.0;
                    let mut v = axis_truth(k, pos[k], &truth_t);
                    if backward {
                        v[k] += reversal_um[k];
                    }
                    let v = v.map(|x| x + noise(0.1));
                    push(
                        Instrument::laser(k),
                        pos,
                        v,
                        if backward { -1 } else { 1 },
                        &mut noise,
                    );
                }
            }
            let sp = spindle_truth(&truth_t);
            let v = std::array::from_fn(|j| if j < 5 { sp[j] + noise(0.2) } else { f64::NAN });
            push(
                Instrument::Spindle,
                [280.0, 200.0, -100.0],
                v,
                1,
                &mut noise,
            );
            let sq = squareness_truth(&truth_t);
            let v = std::array::from_fn(|j| {
                if j >= 3 {
                    sq[j - 3] + noise(0.2)
                } else {
                    f64::NAN
                }
            });
            push(
                Instrument::Squareness,
                [280.0, 200.0, -225.0],
                v,
                1,
                &mut noise,
            );
        }
    }
    Dataset {
        origin: None,
        sensor_names: SENSORS.iter().map(|s| s.to_string()).collect(),
        records,
    }
}

/// The reference machine's feature set (ambient history 8 h, spindle nose rate 5 min, axis
/// feeds 1 h), `hidden` units per net, every residual net kept (so a query evaluates them),
/// few epochs (the tests need a trained model, not a good one).
pub fn reference_like_settings(hidden: usize) -> Settings {
    Settings {
        seed: 1,
        hidden_candidates: vec![hidden],
        max_epochs: 12,
        residual_net_min_gain: f64::NEG_INFINITY,
        history_taus_s: vec![8.0 * 3600.0],
        history_sensors: vec!["Amb".into()],
        spindle_history_taus_s: vec![300.0],
        spindle_history_sensors: vec!["BYB".into()],
        axis_feed_taus_s: vec![3600.0],
        ..Settings::default()
    }
}

/// A hybrid model with the reference machine's features and `hidden` units per net, trained on
/// four synthetic cycles.
pub fn trained(hidden: usize) -> HybridPredictor {
    let ds = dataset(&[4.0, 7.0, 5.5, 3.0], 11);
    train_hybrid(&ds, &geometry(), &reference_like_settings(hidden))
        .expect("the synthetic data train")
        .0
}

/// A random commanded position in the travels.
pub fn random_p_mm(rng: &mut StdRng) -> [f64; 3] {
    std::array::from_fn(|k| rng.random_range(TRAVEL_MM[k].0..TRAVEL_MM[k].1))
}
