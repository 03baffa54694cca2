use vmc_twin::campaign::{self, CampaignConfig, ThermalCycle};
use vmc_twin::machine::MachineSpec;
use vmc_twin::predict::predictor::{self, ErrorPredictor, Settings};
use vmc_twin::twin::Twin;

fn main() {
    let seed: u64 = std::env::args().nth(1).unwrap().parse().unwrap();
    let spec = MachineSpec::reference();
    let data = campaign::calibrate(
        &spec,
        &ThermalCycle::calibration_set(),
        &CampaignConfig::new(seed),
    )
    .unwrap();
    let geom = spec.geometry();
    let (mut h, sum) = predictor::train_hybrid(
        &data,
        &geom,
        &Settings {
            seed,
            ..Default::default()
        },
    )
    .unwrap();
    for n in &sum.nets {
        println!(
            "{} h{:?} val {:?}",
            n.name,
            n.hidden_units,
            n.val_rmse
                .iter()
                .map(|v| (v * 100.0).round() / 100.0)
                .collect::<Vec<_>>()
        );
    }
    let twin = Twin::new(&spec, seed).unwrap();
    let temps = twin.sensor_readings().values_degc;
    for q in [
        [100.0, 100.0, -100.0],
        [300.0, 200.0, -225.0],
        [500.0, 350.0, -400.0],
    ] {
        let et = twin.elementary_errors(q);
        let ep = h.elementary_errors(q, &temps);
        let true_e = twin.tool_error_mm(q, q, [0.0; 3]);
        let pred = h.predict_error_mm(q, &temps);
        println!(
            "q {q:?} true E {:?} pred {:?}",
            true_e.map(|v| (v * 1e4).round() / 10.0),
            pred.map(|v| (v * 1e4).round() / 10.0)
        );
        for a in 0..3 {
            println!(
                "  axis {a}: d lin {:?} d ang {:?}",
                [0, 1, 2]
                    .map(|k| ((ep.axes[a].lin_mm[k] - et.axes[a].lin_mm[k]) * 1e4).round() / 10.0),
                [0, 1, 2].map(
                    |k| ((ep.axes[a].ang_rad[k] - et.axes[a].ang_rad[k]) * 1e7).round() / 10.0
                )
            );
        }
        println!(
            "  sq true {:?} pred {:?}\n  sp pred {:?}",
            et.squareness, ep.squareness, ep.spindle
        );
    }
}
