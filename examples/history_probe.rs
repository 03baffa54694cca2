//! Diagnosis: validation RMSE (calibration cycles only) of each hybrid network for several
//! history-feature settings.
//! `cargo run --release --example history_probe -- SEED`
use vmc_machine::machine::MachineSpec;
use vmc_twin::predict::predictor::{self, Settings};
use vmc_twin::studies::calibration::{self, CampaignConfig, ThermalCycle};

fn main() {
    let seed: u64 = std::env::args()
        .nth(1)
        .map_or(1, |s| s.parse().expect("seed"));
    let spec = MachineSpec::reference();
    let geom = spec.geometry();
    let data = calibration::calibrate(
        &spec,
        &ThermalCycle::calibration_plan(&spec),
        &CampaignConfig::new(seed),
    )
    .unwrap();
    let variants: [(&[&str], Vec<f64>); 5] = [
        (&[], vec![]),
        (&["Amb"], vec![28800.0]),
        (&["Amb", "BXB", "BYB"], vec![600.0, 28800.0]),
        (&["Amb", "BXB", "BYB"], vec![300.0, 28800.0]),
        (&["Amb", "BXB", "BYB", "BXH", "BYH"], vec![600.0, 28800.0]),
    ];
    for (sensors, taus) in variants {
        let settings = Settings {
            seed,
            history_taus_s: taus.clone(),
            history_sensors: sensors.iter().map(|s| s.to_string()).collect(),
            ..Default::default()
        };
        let (_, sum) = predictor::train_hybrid(&data, &geom, &settings).unwrap();
        println!("history {sensors:?} taus {taus:?} val {:?}", sum.val_cycles);
        for n in &sum.nets {
            let f = |v: &Vec<f64>| {
                v.iter()
                    .map(|x| format!("{x:.3}"))
                    .collect::<Vec<_>>()
                    .join(" ")
            };
            println!(
                "  {:<10} h {:?} val [{}] lin [{}]",
                n.name,
                n.hidden_units,
                f(&n.val_rmse),
                f(&n.linear_val_rmse)
            );
        }
    }
}
