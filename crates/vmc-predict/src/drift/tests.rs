use super::*;
use rand::rngs::StdRng;
use rand::SeedableRng;
use rand_distr::{Distribution, Normal};

/// A model predicting a fixed error field `E(q) = c + g·q` (mm), no readings.
#[derive(Clone)]
struct Affine {
    c_mm: [f64; 3],
    g: f64,
    names: Vec<String>,
}

impl ErrorPredictor for Affine {
    fn sensor_names(&self) -> &[String] {
        &self.names
    }
    fn predict_error_mm(&mut self, q: [f64; 3]) -> [f64; 3] {
        [0, 1, 2].map(|a| self.c_mm[a] + self.g * q[a])
    }
    fn observe_readings(&mut self, _: f64, _: &[f64]) {}
    fn observe_spindle_speed(&mut self, _: f64, _: f64) {}
    fn observe_axis_feeds(&mut self, _: f64, _: [f64; 3]) {}
}

fn affine(c_mm: [f64; 3]) -> Affine {
    Affine {
        c_mm,
        g: 1e-5,
        names: Vec::new(),
    }
}

#[test]
fn a_constant_drift_measured_with_noise_is_estimated_as_the_mean_of_the_measurements() {
    let mut f = DriftFilter::new(0.01, 0.5, 10.0).unwrap();
    let mut rng = StdRng::seed_from_u64(3);
    let noise = Normal::new(0.0, 0.5e-3).unwrap();
    let truth = [0.004, -0.002, 0.0031];
    let mut mean = [0.0; 3];
    for k in 0..50 {
        let y = truth.map(|b| Some(b + noise.sample(&mut rng)));
        for a in 0..3 {
            mean[a] += y[a].unwrap_or(0.0) / 50.0;
        }
        f.update(k as f64 * 1800.0, y);
    }
    for a in 0..3 {
        // With a walk this slow the filter is the least-squares constant: the measurements'
        // mean (within 0.02 µm), itself within 5σ of the mean (0.35 µm) of the truth.
        let got = f.drift_mm()[a];
        assert!(
            (got - mean[a]).abs() < 0.02e-3,
            "axis {a}: {got} vs mean {}",
            mean[a]
        );
        assert!((got - truth[a]).abs() < 0.35e-3, "axis {a}: {got}");
    }
}

#[test]
fn the_first_measurement_is_taken_almost_whole_and_the_variance_follows_the_formula() {
    let mut f = DriftFilter::new(2.0, 0.5, 10.0).unwrap();
    let innov = f.update(0.0, [Some(0.003), None, None]);
    assert_eq!(innov, [0.003, 0.0, 0.0]);
    // K = 100 / (100 + 0.25).
    let k = 100.0 / 100.25;
    assert!((f.drift_mm()[0] - k * 0.003).abs() < 1e-15);
    assert_eq!(f.drift_mm()[1], 0.0);
    let p = (1.0 - k) * 100e-6;
    assert!((f.variance_mm2_at(0.0)[0] - p).abs() < 1e-18);
    // After half an hour the walk adds 4 µm²/h × 0.5 h.
    let grown = f.variance_mm2_at(1800.0)[0];
    assert!((grown - (p + 2.0e-6)).abs() < 1e-15, "{grown}");
    // An axis never measured keeps its initial variance (its clock has not started).
    assert!((f.variance_mm2_at(1800.0)[1] - 100e-6).abs() < 1e-18);
}

#[test]
fn a_random_walk_is_tracked_better_than_by_the_last_measurement_alone() {
    // A slow walk (0.3 µm/√h) seen with 0.8 µm noise every 30 min: the filter averages.
    let (walk, sigma) = (0.3, 0.8);
    let mut f = DriftFilter::new(walk, sigma, 5.0).unwrap();
    let mut rng = StdRng::seed_from_u64(11);
    let step = Normal::new(0.0, walk * 1e-3 * 0.5f64.sqrt()).unwrap();
    let noise = Normal::new(0.0, sigma * 1e-3).unwrap();
    let (mut b, mut se_filter, mut se_raw) = (0.0, 0.0, 0.0);
    for k in 0..400 {
        b += step.sample(&mut rng);
        let y = b + noise.sample(&mut rng);
        f.update(k as f64 * 1800.0, [Some(y), None, None]);
        if k >= 20 {
            se_filter += (f.drift_mm()[0] - b).powi(2);
            se_raw += (y - b).powi(2);
        }
    }
    assert!(
        se_filter < 0.5 * se_raw,
        "filter {se_filter:e} raw {se_raw:e}"
    );
}

#[test]
fn bad_settings_are_refused_by_name() {
    assert_eq!(
        DriftFilter::new(1.0, 0.0, 1.0),
        Err(DriftSettingError {
            field: "measurement_sigma_um",
            value: 0.0
        })
    );
    assert!(DriftFilter::new(f64::NAN, 1.0, 1.0).is_err());
    // A measurement that is not a number changes nothing.
    let mut f = DriftFilter::new(1.0, 1.0, 1.0).unwrap();
    f.update(0.0, [Some(f64::NAN), None, None]);
    assert_eq!(f.drift_mm(), [0.0; 3]);
}

/// Latched touches of a sphere at `centre` (contact radius `rc`) on a machine whose true error
/// is the model's plus `missed_mm`: the ball reaches the contact where q + E_true(q) = contact.
fn touches(
    model: &mut Affine,
    centre: [f64; 3],
    rc: f64,
    missed_mm: [f64; 3],
) -> Vec<LatchedTouch> {
    let mut out = Vec::new();
    for (axis, sign) in [(0, 1.0), (0, -1.0), (1, 1.0), (1, -1.0), (2, -1.0)] {
        let mut contact = centre;
        contact[axis] -= sign * rc;
        // Solve q + E_model(q) + missed = contact by fixed point.
        let mut q = contact;
        for _ in 0..5 {
            let e = model.predict_error_mm(q);
            q = [0, 1, 2].map(|a| contact[a] - e[a] - missed_mm[a]);
        }
        out.push(LatchedTouch {
            axis_mm: q,
            axis,
            sign,
        });
    }
    out
}

#[test]
fn probed_minus_reference_gives_the_error_the_model_missed() {
    let mut model = affine([0.01, -0.02, 0.015]);
    let centre = [40.0, 40.0, -377.0];
    let cold = touches(&mut model, centre, 15.5, [0.0; 3]);
    let fix = ArtefactFix {
        reference_mm: artefact_position_mm(&mut model, &cold),
    };
    // Sphere: X and Y from opposite touches average to the centre; Z from the top.
    let r = fix.reference_mm;
    assert!((r[0].unwrap() - 40.0).abs() < 1e-9 && (r[1].unwrap() - 40.0).abs() < 1e-9);
    assert!((r[2].unwrap() - (-377.0 + 15.5)).abs() < 1e-9);
    let missed = [0.002, -0.001, -0.003];
    let warm = touches(&mut model, centre, 15.5, missed);
    let d = fix.drift_mm(artefact_position_mm(&mut model, &warm));
    for a in 0..3 {
        assert!((d[a].unwrap() - missed[a]).abs() < 1e-9, "{d:?}");
    }
    // The corrected model predicts the whole error there.
    let mut f = DriftFilter::new(1.0, 1e-3, 100.0).unwrap();
    f.update(0.0, d);
    let mut with = WithDrift::new(model.clone(), f);
    let q = warm[4].axis_mm;
    let e_true = [0, 1, 2].map(|a| model.predict_error_mm(q)[a] + missed[a]);
    let e = with.predict_error_mm(q);
    for a in 0..3 {
        assert!((e[a] - e_true[a]).abs() < 1e-8);
    }
}
