//! Synthetic calibration data for the predictor tests: a known smooth ground truth of position
//! and temperature (not the twin), sampled like the instruments would, with noise.
//!
//! Sensors `S1, S2, S3` drive the errors; `Amb` drifts but drives nothing. Each cycle heats for
//! 3 h with its own amplitude, then cools; the sensors have different time constants so their
//! ratios change along a cycle (they are not collinear).

use std::f64::consts::PI;

use rand::rngs::StdRng;
use rand::{RngExt, SeedableRng};
use rand_distr::{Distribution, Normal};

use crate::dataset::{Dataset, Instrument, Record};
use crate::predictor::ErrorPredictor;
use crate::synthesis::{
    first_order_error_mm, AxisErrors, Chain, ElementaryErrors, MachineGeometry, SpindleDrift,
    Squareness,
};

/// Sensor names of the synthetic machine.
pub const SENSORS: [&str; 4] = ["S1", "S2", "S3", "Amb"];
/// Axis travels, mm (min, max).
pub const TRAVEL_MM: [(f64, f64); 3] = [(0.0, 560.0), (0.0, 400.0), (-450.0, 0.0)];
/// Laser steps along X, Y, Z, mm.
const STEP_MM: [f64; 3] = [40.0, 40.0, 45.0];

/// The synthetic machine's nominal geometry.
pub fn geometry() -> MachineGeometry {
    MachineGeometry {
        chain: Chain::parse("w X Y b Z t").expect("valid chain"),
        tool_offset_mm: [0.0, 0.0, -150.0],
    }
}

/// Sensor temperatures (°C) at time `t_s` of a cycle with heating amplitude `amp_degc`.
pub fn temps_degc(amp_degc: f64, t_s: f64) -> Vec<f64> {
    let heat_s = 3.0 * 3600.0;
    let taus = [1200.0, 2400.0, 4000.0];
    let gains = [1.0, 0.7, 0.45];
    let mut t: Vec<f64> = (0..3)
        .map(|i| {
            let rise = |t: f64| 1.0 - (-t / taus[i]).exp();
            let dt = if t_s <= heat_s {
                rise(t_s)
            } else {
                rise(heat_s) * (-(t_s - heat_s) / taus[i]).exp()
            };
            20.0 + amp_degc * gains[i] * dt
        })
        .collect();
    t.push(20.0 + 0.5 * (2.0 * PI * t_s / 14400.0 + amp_degc).sin());
    t
}

/// True motion errors of axis `k` at position `s_mm`: dx, dy, dz (µm), rx, ry, rz (µrad).
pub fn axis_errors(k: usize, s_mm: f64, temps: &[f64]) -> [f64; 6] {
    let dt = [temps[0] - 20.0, temps[1] - 20.0, temps[2] - 20.0];
    let (lo, hi) = TRAVEL_MM[k];
    let s = (s_mm - lo) / (hi - lo);
    let shapes = [
        s * s,
        (PI * s).sin(),
        s * (1.0 - s),
        (2.0 * s).cos(),
        s - 0.5,
        -s * s,
    ];
    let mut v = [0.0; 6];
    for j in 0..6 {
        let amp = 2.0 + ((k * 6 + j) % 4) as f64;
        let th = 0.6 * dt[(j + k) % 3] + 0.3 * dt[(j + k + 1) % 3];
        let gain = 0.15 + 0.05 * ((j + 2 * k) % 3) as f64;
        v[j] = amp * shapes[j] + gain * th * (1.0 + s);
    }
    // Thermal expansion of the axis's own scale: 11 µm/°C/m.
    v[k] += 0.011 * (s_mm - lo) * (0.7 * dt[0] + 0.3 * dt[1]);
    v
}

/// True spindle drifts: δx, δy, δz (µm), εx, εy (µrad).
pub fn spindle(temps: &[f64]) -> [f64; 5] {
    let d = [temps[0] - 20.0, temps[1] - 20.0, temps[2] - 20.0];
    [
        0.3 * d[0] - 0.1 * d[2],
        0.5 * d[1] + 0.05 * d[0] * d[0],
        -(3.0 * d[0] + 1.5 * d[1] - 0.5 * d[2]) + 0.1 * d[0] * d[1],
        0.4 * d[1],
        -0.3 * d[0] + 0.2 * d[2],
    ]
}

/// True squareness α_yz, α_xz, α_xy (µrad).
pub fn squareness(temps: &[f64]) -> [f64; 3] {
    let d = [temps[0] - 20.0, temps[1] - 20.0, temps[2] - 20.0];
    [5.0 + 0.3 * d[2], -8.0 + 0.5 * d[1], 12.0 - 0.2 * d[0]]
}

/// True elementary errors at `q` in mm and rad.
pub fn elementary(q: [f64; 3], temps: &[f64]) -> ElementaryErrors {
    let mut e = ElementaryErrors::default();
    for (k, axis) in e.axes.iter_mut().enumerate() {
        let v = axis_errors(k, q[k], temps);
        *axis = AxisErrors {
            lin_mm: [v[0] * 1e-3, v[1] * 1e-3, v[2] * 1e-3],
            ang_rad: [v[3] * 1e-6, v[4] * 1e-6, v[5] * 1e-6],
        };
    }
    let sp = spindle(temps);
    e.spindle = SpindleDrift {
        lin_mm: [sp[0] * 1e-3, sp[1] * 1e-3, sp[2] * 1e-3],
        tilt_rad: [sp[3] * 1e-6, sp[4] * 1e-6],
    };
    let sq = squareness(temps);
    e.squareness = Squareness {
        yz_rad: sq[0] * 1e-6,
        xz_rad: sq[1] * 1e-6,
        xy_rad: sq[2] * 1e-6,
    };
    e
}

/// True volumetric error at `q`, mm.
pub fn true_error_mm(q: [f64; 3], temps: &[f64]) -> [f64; 3] {
    let e = first_order_error_mm(&geometry(), q, &elementary(q, temps));
    [e.x, e.y, e.z]
}

/// A random point in the working volume.
pub fn random_q(rng: &mut StdRng) -> [f64; 3] {
    std::array::from_fn(|k| rng.random_range(TRAVEL_MM[k].0..TRAVEL_MM[k].1))
}

/// A calibration dataset of cycles with heating amplitudes `amps_degc`, all instruments,
/// one measurement round every 20 min over 4 h. Noise: 0.1 µm / 0.1 µrad (laser),
/// 0.2 µm / 0.2 µrad (spindle, squareness), 0.3 µm (volumetric), 0.02 °C (sensors).
pub fn dataset(amps_degc: &[f64], seed: u64) -> Dataset {
    let mut rng_state = StdRng::seed_from_u64(seed);
    let rng = &mut rng_state;
    let noise =
        |rng: &mut StdRng, sigma: f64| Normal::new(0.0, sigma).map_or(0.0, |n| n.sample(rng));
    let mut records = Vec::new();
    for (c, &amp) in amps_degc.iter().enumerate() {
        let cycle = format!("cycle{c}");
        for step in 0..=12 {
            let t_s = step as f64 * 1200.0;
            let truth_t = temps_degc(amp, t_s);
            let mut record = |rng: &mut StdRng, instrument, pos_mm, values: [f64; 6]| {
                let temps = truth_t.iter().map(|t| t + noise(rng, 0.02)).collect();
                records.push(Record {
                    cycle: cycle.clone(),
                    time_s: t_s,
                    instrument,
                    pos_mm,
                    values,
                    temps_degc: temps,
                    dir: 1,
                    spindle_rpm: None,
                    axis_feed_mm_per_min: None,
                });
            };
            for k in 0..3 {
                let (lo, hi) = TRAVEL_MM[k];
                let n = ((hi - lo) / STEP_MM[k]).round() as usize;
                for i in 0..=n {
                    let mut pos = [0.0, 0.0, -100.0];
                    pos[k] = lo + i as f64 * STEP_MM[k];
                    let v = axis_errors(k, pos[k], &truth_t);
                    let vals = std::array::from_fn(|j| v[j] + noise(rng, 0.1));
                    record(rng, Instrument::laser(k), pos, vals);
                }
            }
            let sp = spindle(&truth_t);
            let mut vals = [f64::NAN; 6];
            for j in 0..5 {
                vals[j] = sp[j] + noise(rng, 0.2);
            }
            record(rng, Instrument::Spindle, [280.0, 200.0, -100.0], vals);
            let sq = squareness(&truth_t);
            let mut vals = [f64::NAN; 6];
            for j in 0..3 {
                vals[3 + j] = sq[j] + noise(rng, 0.2);
            }
            record(rng, Instrument::Squareness, [280.0, 200.0, -225.0], vals);
            for _ in 0..12 {
                let q = random_q(rng);
                let e = true_error_mm(q, &truth_t);
                let mut vals = [f64::NAN; 6];
                for j in 0..3 {
                    vals[j] = e[j] * 1e3 + noise(rng, 0.3);
                }
                record(rng, Instrument::Volumetric, q, vals);
            }
        }
    }
    Dataset {
        origin: None,
        sensor_names: SENSORS.iter().map(|s| s.to_string()).collect(),
        records,
    }
}

/// Held-out evaluation points: `(q, temps, true E mm)` over a cycle of amplitude `amp_degc`.
pub fn held_out(amp_degc: f64, seed: u64) -> Vec<([f64; 3], Vec<f64>, [f64; 3])> {
    let mut rng = StdRng::seed_from_u64(seed);
    (0..200)
        .map(|i| {
            let t_s = (i % 25) as f64 * 600.0;
            let temps = temps_degc(amp_degc, t_s);
            let q = random_q(&mut rng);
            let e = true_error_mm(q, &temps);
            (q, temps, e)
        })
        .collect()
}

/// The prediction of `p` at `q` (mm) for the readings `temps` (°C): observes them, then
/// queries. The readings are observed at time 0, which only a model without history features
/// may ignore: for one with them, observe the readings' history explicitly.
pub fn predict_at<P: ErrorPredictor>(p: &mut P, q: [f64; 3], temps: &[f64]) -> [f64; 3] {
    p.observe_readings(0.0, temps);
    p.predict_error_mm(q)
}

/// RMS over all components of `pred − truth` and of `truth`, in µm.
pub fn rms_um(pairs: &[([f64; 3], [f64; 3])]) -> (f64, f64) {
    let n = (pairs.len() * 3) as f64;
    let (mut se, mut st) = (0.0, 0.0);
    for (p, t) in pairs {
        for k in 0..3 {
            se += ((p[k] - t[k]) * 1e3).powi(2);
            st += (t[k] * 1e3).powi(2);
        }
    }
    ((se / n).sqrt(), (st / n).sqrt())
}
