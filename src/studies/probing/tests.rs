use super::*;
use vmc_machine::thermal::AmbientProfile;
use vmc_predict::predictor::PredictError;

/// A model that predicts no error at all: the probe's drift is then the machine's whole change
/// since the cold qualification.
#[derive(Clone)]
struct Nothing {
    names: Vec<String>,
}

impl ErrorPredictor for Nothing {
    fn sensor_names(&self) -> &[String] {
        &self.names
    }
    fn predict_error_mm(&mut self, _q_mm: [f64; 3]) -> [f64; 3] {
        [0.0; 3]
    }
    fn observe_readings(&mut self, _: f64, _: &[f64]) {}
    fn observe_spindle_speed(&mut self, _: f64, _: f64) {}
    fn observe_axis_feeds(&mut self, _: f64, _: [f64; 3]) {}
    fn change_tool(&mut self, _: [f64; 3]) -> Result<(), PredictError> {
        Ok(())
    }
}

fn noise_free(spec: &MachineSpec) -> Probing {
    let mut p = Probing::every(spec, 60.0);
    p.probe.repeatability_2sigma_um = 0.0;
    p.probe.servo_period_s = 1e-7;
    p
}

#[test]
fn the_tops_come_last_and_a_cycle_takes_the_machine_time_it_charges() {
    let spec = MachineSpec::reference();
    let p = Probing::every(&spec, 60.0);
    let seq = p.sequence();
    let tops = seq.iter().filter(|t| t.1 == 2).count();
    assert_eq!(tops, 4 * p.top_repeats);
    assert!(seq[seq.len() - tops..].iter().all(|t| t.1 == 2));
    assert_eq!(seq.len(), p.touches_per_cycle());
    let mut twin = Twin::with_noise_seed(&spec, 3, 4).unwrap();
    let mut ctrl = Compensator::new(Nothing { names: vec![] });
    let mut on = ProbeOnTwin::new(p.probe, 1).unwrap();
    let t0 = twin.time_s();
    let readings = run_cycle(
        &mut twin,
        &p,
        &mut ctrl,
        Compensator::predictor_mut,
        &mut on,
    )
    .unwrap();
    assert!((twin.time_s() - t0 - p.cycle_s()).abs() < 1e-6);
    // Every touch tripped, each at its own instant, in order.
    assert_eq!(readings.len(), seq.len());
    assert!(readings.windows(2).all(|w| w[1].time_s > w[0].time_s + 1.0));
}

#[test]
fn on_a_warm_machine_the_probe_measures_the_z_drift_the_tool_has_at_the_tops() {
    // Differential check of frames and signs (the truth read by the test only): the probe's Z
    // drift of each top against the error the diagonal measurement sees with the machine's
    // tool at the same point, warm minus cold. The warm machine is soaked at a steady 35 °C so
    // that nothing moves during the cycle.
    let spec = MachineSpec::reference();
    let seed = 5;
    let p = noise_free(&spec);
    let model = Nothing { names: vec![] };
    let fix = qualify(&spec, seed, &p, &model).unwrap();
    let mut warm = Twin::with_noise_seed(&spec, seed, 11).unwrap();
    warm.set_ambient(AmbientProfile::Constant { temp_degc: 35.0 })
        .unwrap();
    warm.soak_degc(35.0).unwrap();
    let cold = Twin::with_noise_seed(&spec, seed, 12).unwrap();
    let mut ctrl = Compensator::new(model);
    let mut on = ProbeOnTwin::new(p.probe, 2).unwrap();
    let readings = run_cycle(
        &mut warm,
        &p,
        &mut ctrl,
        Compensator::predictor_mut,
        &mut on,
    )
    .unwrap();
    let rc = p.sphere_radius_mm + p.probe.ball_radius_mm;
    let z: Vec<_> = drift_measurements(&readings, &fix)
        .into_iter()
        .filter(|m| m.1 == 2)
        .collect();
    assert_eq!(z.len(), 4);
    for (i, m) in z.iter().enumerate() {
        let c = p.sphere_centres_mm[i];
        let top = [c[0], c[1], c[2] + rc];
        let truth_um = (warm.tool_error_mm(top, top, [0.0; 3]).z
            - cold.tool_error_mm(top, top, [0.0; 3]).z)
            * 1e3;
        let probed_um = m.3 * 1e3;
        assert!(
            truth_um.abs() > 1.0,
            "sphere {i}: the machine drifted {truth_um} µm"
        );
        // The machine's own approach scatter (0.3 µm σ on Z, nine touches) is left.
        assert!(
            (probed_um - truth_um).abs() < 0.5,
            "sphere {i}: probed {probed_um:.2} µm, the tool's drift {truth_um:.2} µm"
        );
    }
}
