//! The hybrid model of one development machine, trained once and cached under
//! `target/probing-models/` (shared by the probing diagnosis examples).
use vmc_machine::machine::MachineSpec;
use vmc_twin::predict::predictor::{self, HybridPredictor, Settings};
use vmc_twin::studies::calibration::{self, CampaignConfig, ThermalCycle};
use vmc_twin::studies::campaign::{self, ForMachine};

/// The campaign's hybrid model of machine `seed` (trained on its calibration data).
pub fn model(spec: &MachineSpec, seed: u64) -> HybridPredictor {
    let dir = std::path::Path::new("target/probing-models");
    let path = dir.join(format!("hybrid_seed{seed}.json"));
    if let Ok(text) = std::fs::read_to_string(&path) {
        return HybridPredictor::from_json_str(&text).unwrap();
    }
    let data = calibration::calibrate(
        spec,
        &ThermalCycle::calibration_plan(spec),
        &CampaignConfig::new(seed),
    )
    .unwrap();
    let s = campaign::fit_to_data(
        Settings {
            seed,
            ..Settings::for_machine(spec)
        },
        &data,
    );
    let (h, _) = predictor::train_hybrid(&data, &spec.geometry(), &s).unwrap();
    std::fs::create_dir_all(dir).unwrap();
    std::fs::write(&path, h.to_json_string().unwrap()).unwrap();
    h
}
