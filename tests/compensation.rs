//! End-to-end acceptance of the compensation: the twin is calibrated with virtual
//! instruments, the hybrid predictor is trained on that dataset only, and every face and body
//! diagonal is run under held-out thermal states (atypical cycles and stress cycles never used
//! in calibration, other noise seeds) with the predictor in the loop. Three machine
//! realisations. Every run must remove ≥ 80 % of RMS |E|, and every warm run must leave at most
//! 25 % of its error's thermal part — except the Z-stroke stress state, which does not reach it
//! (docs/results.md says why) and is held to its measured figure so that it cannot slide back.
//!
//! The second test shows the first can fail: the same trained predictor with its temperature
//! inputs frozen at a cold reading (so it knows only the cold geometry) does not reach 80 % on
//! the warm runs.

use vmc_machine::machine::MachineSpec;
use vmc_twin::predict::predictor::{self, ErrorPredictor, HybridPredictor, ModelKind, Settings};
use vmc_twin::studies::calibration::{self, CampaignConfig, ThermalCycle};
use vmc_twin::studies::campaign::ForMachine;
use vmc_twin::studies::campaign::{self, RunReport};

const SEEDS: [u64; 3] = [1, 2, 3];

fn trained(spec: &MachineSpec, seed: u64) -> HybridPredictor {
    let data = calibration::calibrate(
        spec,
        &ThermalCycle::calibration_plan(spec),
        &CampaignConfig::new(seed),
    )
    .expect("campaign runs");
    let settings = campaign::fit_to_data(
        Settings {
            seed,
            ..Settings::for_machine(spec)
        },
        &data,
    );
    predictor::train_hybrid(&data, &spec.geometry(), &settings)
        .expect("training succeeds")
        .0
}

/// The trained predictor with every observed reading replaced by a fixed cold one.
#[derive(Clone)]
struct FrozenTemps {
    inner: HybridPredictor,
    cold_degc: Vec<f64>,
}

impl ErrorPredictor for FrozenTemps {
    fn sensor_names(&self) -> &[String] {
        self.inner.sensor_names()
    }
    fn predict_error_mm(&mut self, q_mm: [f64; 3]) -> [f64; 3] {
        self.inner.predict_error_mm(q_mm)
    }
    fn observe_readings(&mut self, time_s: f64, _temps_degc: &[f64]) {
        self.inner.observe_readings(time_s, &self.cold_degc);
    }
    // What the controller commanded is not a temperature: it passes unchanged.
    fn observe_spindle_speed(&mut self, time_s: f64, rpm: f64) {
        self.inner.observe_spindle_speed(time_s, rpm);
    }
    fn observe_axis_feeds(&mut self, time_s: f64, feeds_mm_per_min: [f64; 3]) {
        self.inner.observe_axis_feeds(time_s, feeds_mm_per_min);
    }
}

fn is_warm(r: &RunReport) -> bool {
    r.thermal_state != "cold"
}

/// The stress state whose residual share of the thermal part is not within 25 %: its thermal part
/// is 1.2–2.5 µm RMS, and the non-repeatability alone leaves about 0.46 µm RMS (measured:
/// 38–49 % at worst; docs/results.md).
const Z_STROKES: &str = "stress_z_strokes@3h";

#[test]
fn hybrid_compensation_removes_at_least_80_percent_on_every_diagonal_held_out_state_and_seed() {
    let spec = MachineSpec::reference();
    let plans = campaign::diagonal_plans(&spec).unwrap();
    let mut runs = Vec::new();
    for seed in SEEDS {
        let model = trained(&spec, seed);
        let states = calibration::evaluation_states(&spec, seed);
        runs.extend(
            campaign::evaluate_predictor(&spec, seed, ModelKind::Hybrid, &model, &states, &plans)
                .unwrap(),
        );
    }
    // 7 diagonals × 12 states × 3 seeds.
    let n_states = calibration::evaluation_states(&spec, 1).len();
    assert_eq!(n_states, 12);
    assert_eq!(runs.len(), 7 * n_states * SEEDS.len());
    let mut worst: Vec<(f64, String)> = Vec::new();
    for diag in ["XY", "YZ", "XZ", "PPP", "NPP", "PNP", "PPN"] {
        let of_diag: Vec<&RunReport> = runs.iter().filter(|r| r.diagonal == diag).collect();
        assert_eq!(of_diag.len(), n_states * SEEDS.len(), "{diag}");
        for r in of_diag {
            worst.push((
                r.reduction,
                format!("{diag} {} seed {}", r.thermal_state, r.seed),
            ));
            assert!(
                r.reduction >= 0.80,
                "{diag} at {} (seed {}): RMS |E| {:.2} → {:.2} µm, reduction {:.1} % < 80 %",
                r.thermal_state,
                r.seed,
                r.rms_before_um,
                r.rms_after_um,
                r.reduction * 100.0
            );
        }
    }
    worst.sort_by(|a, b| a.0.total_cmp(&b.0));
    println!("worst runs: {:?}", &worst[..3]);
    // The residual as a share of the thermal part, on every warm run.
    let mut shares: Vec<(f64, String)> = runs
        .iter()
        .filter_map(|r| {
            r.residual_share_of_thermal.map(|s| {
                (
                    s,
                    format!("{} {} seed {}", r.diagonal, r.thermal_state, r.seed),
                )
            })
        })
        .collect();
    shares.sort_by(|a, b| b.0.total_cmp(&a.0));
    println!(
        "largest residual shares of the thermal part: {:?}",
        &shares[..3]
    );
    // Every warm state but the cold one has thermal parts well above the 1 µm threshold.
    assert!(shares.len() >= 7 * 10 * SEEDS.len());
    for (s, at) in &shares {
        let limit = if at.contains(Z_STROKES) { 0.55 } else { 0.25 };
        assert!(
            *s <= limit,
            "{at}: residual {:.0} % of the thermal part",
            s * 100.0
        );
    }
    // Regression guards on the largest compensated error: measured 2.08 µm on the atypical
    // states (the aim of 2 µm is not reached) and 3.08 µm on the stress states
    // (docs/results.md). The runs are deterministic (same seeds, same bits), so the guards only
    // stop the figures from sliding back.
    for (stress, guard) in [(false, 2.15), (true, 3.15)] {
        let (max_after, at) = runs
            .iter()
            .filter(|r| r.thermal_state.starts_with("stress_") == stress)
            .map(|r| {
                (
                    r.max_after_um,
                    format!("{} {} seed {}", r.diagonal, r.thermal_state, r.seed),
                )
            })
            .max_by(|a, b| a.0.total_cmp(&b.0))
            .unwrap();
        println!("max residual |E| {max_after:.2} µm ({at})");
        assert!(
            max_after <= guard,
            "max residual |E| {max_after:.2} µm at {at} > {guard} µm"
        );
    }
}

#[test]
fn a_predictor_blind_to_temperature_does_not_reach_80_percent_on_warm_runs() {
    let spec = MachineSpec::reference();
    let plans = campaign::diagonal_plans(&spec).unwrap();
    let seed = SEEDS[0];
    let model = trained(&spec, seed);
    let cold_degc = vec![20.0; model.sensor_names().len()];
    let frozen = FrozenTemps {
        inner: model.clone(),
        cold_degc,
    };
    let states = calibration::evaluation_states(&spec, seed);
    let blind =
        campaign::evaluate_predictor(&spec, seed, ModelKind::Hybrid, &frozen, &states, &plans)
            .unwrap();
    let full =
        campaign::evaluate_predictor(&spec, seed, ModelKind::Hybrid, &model, &states, &plans)
            .unwrap();
    let mean = |runs: &[RunReport]| {
        let warm: Vec<f64> = runs
            .iter()
            .filter(|r| is_warm(r))
            .map(|r| r.reduction)
            .collect();
        warm.iter().sum::<f64>() / warm.len() as f64
    };
    let (blind_mean, full_mean) = (mean(&blind), mean(&full));
    println!(
        "mean reduction on warm runs: temperature-blind {:.1} %, full {:.1} %",
        blind_mean * 100.0,
        full_mean * 100.0
    );
    assert!(
        blind_mean < 0.80,
        "blind predictor reached {:.1} %",
        blind_mean * 100.0
    );
    assert!(full_mean > blind_mean + 0.2);
    // On the cold runs the blind predictor is as good as the full one: what it lacks is thermal.
    let cold = |runs: &[RunReport]| {
        runs.iter()
            .filter(|r| !is_warm(r))
            .map(|r| r.reduction)
            .sum::<f64>()
    };
    assert!((cold(&blind) - cold(&full)).abs() / 7.0 < 0.05);
}
