//! End-to-end acceptance of the compensation: the twin is calibrated with virtual
//! instruments, the hybrid predictor is trained on that dataset only, and every face and body
//! diagonal is run under held-out thermal states (atypical cycles never used in calibration,
//! other noise seeds) with the predictor in the loop. Three machine realisations.
//!
//! The second test shows the first can fail: the same trained predictor with its temperature
//! inputs frozen at a cold reading (so it knows only the cold geometry) does not reach 80 % on
//! the warm runs.

use vmc_twin::calibration::{self, CampaignConfig, ThermalCycle};
use vmc_twin::machine::MachineSpec;
use vmc_twin::predict::predictor::{self, ErrorPredictor, HybridPredictor, ModelKind, Settings};
use vmc_twin::study::ForMachine;
use vmc_twin::study::{self, RunReport};

const SEEDS: [u64; 3] = [1, 2, 3];

fn trained(spec: &MachineSpec, seed: u64) -> HybridPredictor {
    let data = calibration::calibrate(
        spec,
        &ThermalCycle::calibration_plan(&spec),
        &CampaignConfig::new(seed),
    )
    .expect("campaign runs");
    let settings = Settings {
        seed,
        ..Settings::for_machine(spec)
    };
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
}

fn is_warm(r: &RunReport) -> bool {
    r.thermal_state != "cold"
}

#[test]
fn hybrid_compensation_removes_at_least_80_percent_on_every_diagonal_held_out_state_and_seed() {
    let spec = MachineSpec::reference();
    let plans = study::diagonal_plans(&spec).unwrap();
    let mut runs = Vec::new();
    for seed in SEEDS {
        let model = trained(&spec, seed);
        let states = calibration::evaluation_states(&spec, seed);
        runs.extend(
            study::evaluate_predictor(&spec, seed, ModelKind::Hybrid, &model, &states, &plans)
                .unwrap(),
        );
    }
    // 7 diagonals × 7 states × 3 seeds.
    assert_eq!(runs.len(), 7 * 7 * SEEDS.len());
    let mut worst: Vec<(f64, String)> = Vec::new();
    for diag in ["XY", "YZ", "XZ", "PPP", "NPP", "PNP", "PPN"] {
        let of_diag: Vec<&RunReport> = runs.iter().filter(|r| r.diagonal == diag).collect();
        assert_eq!(of_diag.len(), 7 * SEEDS.len(), "{diag}");
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
    // Regression guard on the largest compensated error over all 147 runs: measured 2.48 µm
    // (docs/results.md); the aim of 2 µm is not reached, so
    // this only stops the figure from sliding back (2.06 µm before the bilinear axis parts,
    // chosen on development states, which raised it here; 2.31 µm without the ambient history
    // feature, 7 µm in the first version). The guard stays at 2.5 µm: the runs are
    // deterministic (same seeds, same bits), so it is not widened for the new figure.
    let (max_after, at) = runs
        .iter()
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
        max_after <= 2.5,
        "max residual |E| {max_after:.2} µm at {at} > 2.5 µm"
    );
}

#[test]
fn a_predictor_blind_to_temperature_does_not_reach_80_percent_on_warm_runs() {
    let spec = MachineSpec::reference();
    let plans = study::diagonal_plans(&spec).unwrap();
    let seed = SEEDS[0];
    let model = trained(&spec, seed);
    let cold_degc = vec![20.0; model.sensor_names().len()];
    let frozen = FrozenTemps {
        inner: model.clone(),
        cold_degc,
    };
    let states = calibration::evaluation_states(&spec, seed);
    let blind = study::evaluate_predictor(&spec, seed, ModelKind::Hybrid, &frozen, &states, &plans)
        .unwrap();
    let full =
        study::evaluate_predictor(&spec, seed, ModelKind::Hybrid, &model, &states, &plans).unwrap();
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
