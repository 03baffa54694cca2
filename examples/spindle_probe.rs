//! Diagnosis (truth side): how much of the spindle's axial drift can the readings tell, right
//! after a stop?
//!
//! Samples the truth (the twin's spindle δz) and the readings every 30 s while each cycle's duty
//! runs, fits linear models by least squares on the typical (calibration) cycles, noise-free and
//! dense — a bound, better data than any campaign — and scores them on the atypical ones (the
//! held-out evaluation cycles and the selection-only cycles), overall and in the first 3 min
//! after each spindle stop, where a diagonal test runs. Inputs compared:
//! - the readings;
//! - the readings and the nose rate (nose reading minus its 5 min low-pass filter), as the
//!   predictor's spindle part;
//! - those and low-pass filters of the spindle speed (τ = 2, 10, 30 min) — what the controller
//!   commanded, shown to say what it is worth (the hybrid takes it with `--spindle-speed`).
//!
//! `cargo run --release --example spindle_probe -- SEED`
use vmc_machine::machine::MachineSpec;
use vmc_machine::twin::{sub_seed, Twin};
use vmc_twin::predict::linreg::LinearModel;
use vmc_twin::predict::nn::Samples;
use vmc_twin::studies::calibration::{self, ThermalCycle};

const SPEED_TAUS_S: [f64; 3] = [120.0, 600.0, 1800.0];
const NOSE_TAU_S: f64 = 300.0;

/// Follows the readings at every thermal step: the nose sensor's low-pass filter.
struct NoseFilter {
    idx: usize,
    lp: Option<f64>,
    last_s: f64,
}

impl vmc_machine::sim::Controller for NoseFilter {
    fn axis_command_mm(&mut self, p_mm: [f64; 3]) -> [f64; 3] {
        p_mm
    }

    fn on_readings(&mut self, time_s: f64, values_degc: &[f64]) {
        let x = values_degc[self.idx];
        self.lp = Some(match self.lp {
            None => x,
            Some(f) => f + (1.0 - (-(time_s - self.last_s) / NOSE_TAU_S).exp()) * (x - f),
        });
        self.last_s = time_s;
    }

    fn on_spindle_speed(&mut self, _time_s: f64, _rpm: f64) {}

    fn on_axis_feeds(&mut self, _time_s: f64, _feeds_mm_per_min: [f64; 3]) {}
}

/// One sample: readings, nose rate, speed filters, truth δz (µm), seconds since the last stop.
struct Sample {
    readings: Vec<f64>,
    nose_rate: f64,
    speed: Vec<f64>,
    dz_um: f64,
    since_stop_s: f64,
}

fn samples(spec: &MachineSpec, seed: u64, k: u64, cycle: &ThermalCycle) -> Vec<Sample> {
    let mut twin = Twin::with_noise_seed(spec, seed, sub_seed(seed, 6000 + k)).unwrap();
    twin.set_ambient(cycle.ambient.clone()).unwrap();
    let names = twin.sensor_readings().names.to_vec();
    let idx = spec
        .sensors
        .iter()
        .position(|s| s.node == "spindle_nose")
        .and_then(|i| names.iter().position(|n| *n == spec.sensors[i].name))
        .expect("a sensor on the spindle nose");
    let mid = [0, 1, 2].map(|a| 0.5 * (spec.axes.travel_min_mm[a] + spec.axes.travel_max_mm[a]));
    let mut nose = NoseFilter {
        idx,
        lp: None,
        last_s: 0.0,
    };
    let mut speed = [0.0f64; SPEED_TAUS_S.len()];
    let mut since_stop = f64::INFINITY;
    let mut before = 0.0;
    let mut out = Vec::new();
    let end = cycle.duration_s();
    let mut t = 0.0;
    while t < end - 1e-9 {
        let to = (t + 30.0).min(end);
        calibration::drive_with(&mut twin, cycle, 0.0, to, 1.0, Some(&mut nose)).unwrap();
        let rpm = cycle.phase_at(0.5 * (t + to)).spindle_rpm;
        if before > 0.0 && rpm == 0.0 {
            since_stop = 0.0;
        }
        before = rpm;
        since_stop += to - t;
        for (f, tau) in speed.iter_mut().zip(SPEED_TAUS_S) {
            *f += (1.0 - (-(to - t) / tau).exp()) * (rpm / 1000.0 - *f);
        }
        t = to;
        let readings = twin.sensor_readings().values_degc;
        out.push(Sample {
            nose_rate: readings[idx] - nose.lp.unwrap_or(readings[idx]),
            readings,
            speed: speed.to_vec(),
            dz_um: twin.elementary_errors(mid).spindle.lin_mm[2] * 1e3,
            since_stop_s: if rpm == 0.0 {
                since_stop
            } else {
                f64::INFINITY
            },
        });
    }
    out
}

/// The inputs of one variant, from a sample.
type Features = fn(&Sample) -> Vec<f64>;

/// The project's ridge regression (z-scored inputs, a tiny ridge for conditioning) fitted on
/// `train`; residuals on `test`.
fn residuals(train: &[(Vec<f64>, f64)], test: &[(Vec<f64>, f64)]) -> Vec<f64> {
    let xs: Vec<Vec<f64>> = train.iter().map(|(x, _)| x.clone()).collect();
    let ys: Vec<Vec<f64>> = train.iter().map(|(_, y)| vec![*y]).collect();
    let model = LinearModel::fit(&Samples::from_rows(&xs, &ys).unwrap(), 1e-6).unwrap();
    test.iter()
        .map(|(x, y)| model.predict(x).unwrap()[0] - y)
        .collect()
}

fn main() {
    let seed: u64 = std::env::args()
        .nth(1)
        .map_or(21, |s| s.parse().expect("seed"));
    let spec = MachineSpec::reference();
    let collect = |cycles: &[ThermalCycle], base: u64| {
        cycles
            .iter()
            .enumerate()
            .flat_map(|(k, c)| samples(&spec, seed, base + k as u64, c))
            .collect::<Vec<_>>()
    };
    let train = collect(&ThermalCycle::calibration_plan(&spec), 0);
    let mut test_cycles = ThermalCycle::evaluation_set(seed);
    test_cycles.extend(
        vmc_twin::studies::placement::validation_states(seed)
            .into_iter()
            .map(|s| s.cycle),
    );
    test_cycles.dedup_by(|a, b| a.name == b.name);
    let test = collect(&test_cycles, 100);
    let after_stop: Vec<bool> = test.iter().map(|s| s.since_stop_s <= 180.0).collect();
    println!(
        "seed {seed}: spindle δz, {} atypical samples ({} within 3 min of a stop), µm: \
         RMS / max |residual| overall | after a stop",
        test.len(),
        after_stop.iter().filter(|b| **b).count()
    );
    let variants: [(&str, Features); 3] = [
        ("readings", |s| s.readings.clone()),
        ("readings + nose rate", |s| {
            let mut x = s.readings.clone();
            x.push(s.nose_rate);
            x
        }),
        ("… + spindle speed filters (outside §3)", |s| {
            let mut x = s.readings.clone();
            x.push(s.nose_rate);
            x.extend_from_slice(&s.speed);
            x
        }),
    ];
    for (name, f) in variants {
        let rows = |v: &[Sample]| v.iter().map(|s| (f(s), s.dz_um)).collect::<Vec<_>>();
        let r = residuals(&rows(&train), &rows(&test));
        let stats = |keep: &dyn Fn(usize) -> bool| {
            let e: Vec<f64> = r
                .iter()
                .enumerate()
                .filter(|(i, _)| keep(*i))
                .map(|(_, e)| *e)
                .collect();
            let rms = (e.iter().map(|x| x * x).sum::<f64>() / e.len().max(1) as f64).sqrt();
            let max = e.iter().fold(0.0f64, |m, x| m.max(x.abs()));
            format!("{rms:.3} / {max:.3}")
        };
        println!(
            "  {name:<40} {} | {}",
            stats(&|_| true),
            stats(&|i| after_stop[i])
        );
    }
}
