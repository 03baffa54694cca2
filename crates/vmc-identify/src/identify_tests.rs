//! Identification on synthetic probing data from the exact model.

use super::*;
use crate::errors::tests_support::trunnion;
use crate::errors::ErrorState;
use crate::inverse::nominal_linear_axes;

/// A small deterministic generator for the tests (SplitMix64 + Box–Muller); the crate itself
/// draws nothing at random.
pub(crate) struct Rng(pub(crate) u64);

impl Rng {
    pub(crate) fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }
    pub(crate) fn uniform(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }
    pub(crate) fn normal(&mut self) -> f64 {
        let u1 = self.uniform().max(1e-300);
        let u2 = self.uniform();
        (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
    }
}

/// `n` configurations spread over C ∈ [0, 360) and A ∈ [−100, 20] (golden-ratio sequence).
pub(crate) fn spread(n: usize, c_fixed: Option<f64>) -> Vec<[f64; 2]> {
    (0..n)
        .map(|i| {
            let u = (i as f64 * 0.618_033_988_75).fract();
            let v = (i as f64 + 0.5) / n as f64;
            [c_fixed.unwrap_or(360.0 * u), -100.0 + 120.0 * v]
        })
        .collect()
}

fn truth(set: &ParameterSet, rng: &mut Rng) -> Vec<f64> {
    set.params
        .iter()
        .map(|p| {
            let x = 2.0 * rng.uniform() - 1.0;
            if p.component.is_angle() {
                3e-5 * x
            } else {
                0.03 * x
            }
        })
        .collect()
}

/// Centre covariance of a 9-point fit: about 0.6σ across, 1σ along the pole.
fn centre_cov(sigma_mm: f64) -> Matrix3<f64> {
    Matrix3::from_diagonal(&Vector3::new(0.36, 0.36, 1.0)) * sigma_mm.powi(2)
}

pub(crate) fn observe(
    set: &ParameterSet,
    values: &[f64],
    configs: &[[f64; 2]],
    sigma_mm: f64,
    rng: &mut Rng,
) -> Vec<Observation> {
    let g = trunnion();
    let cov = centre_cov(sigma_mm.max(1.25e-4));
    let l = centre_cov(sigma_mm).map(f64::sqrt);
    configs
        .iter()
        .map(|&rot| {
            let q = linear_axes_for(&g, rot, Vector3::zeros(), &|pose: &Pose| {
                set.state_at(values, pose)
            })
            .unwrap();
            let noise = l * Vector3::new(rng.normal(), rng.normal(), rng.normal());
            Observation {
                target_w_mm: [0.0; 3],
                rotary_deg: rot,
                nominal_mm: nominal_linear_axes(&g, rot, Vector3::zeros()),
                measured_mm: (Vector3::from(q) + noise).into(),
                cov_mm2: cov,
                placement: 0,
            }
        })
        .collect()
}

#[test]
fn noise_free_probing_identifies_every_identifiable_parameter_to_1e_6_of_its_value() {
    let g = trunnion();
    let set = ParameterSet::location_and_assembly(&g);
    let mut rng = Rng(11);
    let mut values = truth(&set, &mut rng);
    let configs = spread(50, None);
    // First with every parameter non-zero: the fixed ones' effect is carried by the kept ones
    // exactly to first order; the exact model leaves a second-order part (ε·δ ≈ 1e-9) in them.
    let obs = observe(&set, &values, &configs, 0.0, &mut rng);
    let id = identify(&g, &set, &obs, &IdentifyOptions::default()).unwrap();
    assert!(id.rms_residual_mm < 1e-9, "{}", id.rms_residual_mm);
    assert!(id.linearisation_error_mm > 0.0 && id.linearisation_error_mm < 1e-4);
    for (e, v) in id.estimates.iter().zip(&values) {
        if e.status == Status::Identified {
            assert!(
                (e.value - v).abs() <= 1e-3 * v.abs(),
                "{}: {} vs {v}",
                e.name,
                e.value
            );
        }
    }
    // Then with the fixed ones at zero (the machine as the kept parameters describe it): every
    // identified parameter to 1e-6 of its value.
    for (e, v) in id.estimates.iter().zip(values.iter_mut()) {
        if e.status == Status::Fixed {
            *v = 0.0;
        }
    }
    let obs = observe(&set, &values, &configs, 0.0, &mut rng);
    let id = identify(&g, &set, &obs, &IdentifyOptions::default()).unwrap();
    let mut n_identified = 0;
    for (e, v) in id.estimates.iter().zip(&values) {
        if e.status != Status::Fixed {
            n_identified += 1;
            assert!(
                (e.value - v).abs() <= 1e-6 * v.abs(),
                "{}: {} vs {v}",
                e.name,
                e.value
            );
        }
    }
    assert_eq!(n_identified, 14, "{:#?}", id.relations);
}

#[test]
fn the_offset_of_the_a_line_and_of_the_stylus_are_named_inseparable() {
    let g = trunnion();
    let set = ParameterSet::location_and_assembly(&g);
    let mut rng = Rng(5);
    let obs = observe(
        &set,
        &vec![0.0; set.len()],
        &spread(50, None),
        1.25e-4,
        &mut rng,
    );
    let id = identify(&g, &set, &obs, &IdentifyOptions::default()).unwrap();
    let rel = id
        .relations
        .iter()
        .find(|r| r.fixed == "E_YT")
        .expect("E_YT fixed");
    assert!(rel.message.contains("E_Y0A"), "{}", rel.message);
    assert!(
        rel.message.contains("only their difference E_Y0A − E_YT"),
        "{}",
        rel.message
    );
    assert_eq!(id.rank + id.relations.len(), set.len());
}

#[test]
fn with_noise_the_stated_uncertainty_is_honest_in_100_repetitions() {
    let g = trunnion();
    coverage_in_100_repetitions(&ParameterSet::location_and_assembly(&g), 2024);
}

#[test]
fn with_the_second_harmonics_of_the_rotary_axes_the_uncertainty_stays_honest() {
    // The default model of `identify`: 19 constants and the cos/sin 2θ terms of the twelve
    // rotary motion errors (43 parameters, rank 39).
    let g = trunnion();
    coverage_in_100_repetitions(
        &ParameterSet::location_and_assembly(&g).with_motion_harmonics(&g, 2),
        2025,
    );
}

/// Draws a machine of `set`, probes it 100 times with noise (50 spread configurations) and
/// checks that each identified parameter lies within twice its stated uncertainty about 95 % of
/// the time.
fn coverage_in_100_repetitions(set: &ParameterSet, seed: u64) {
    let g = trunnion();
    let set = set.clone();
    let sigma_mm = 1.25e-4; // 0.25 µm at 2σ
    let configs = spread(50, None);
    let mut rng = Rng(seed);
    let values = truth(&set, &mut rng);
    let mut inside = vec![0usize; set.len()];
    let mut counted = vec![0usize; set.len()];
    for _ in 0..100 {
        let obs = observe(&set, &values, &configs, sigma_mm, &mut rng);
        let id = identify(&g, &set, &obs, &IdentifyOptions::default()).unwrap();
        for (j, e) in id.estimates.iter().enumerate() {
            if e.status == Status::Identified {
                counted[j] += 1;
                // Expanded uncertainty k = 2 (≈ 95 %).
                if (e.value - values[j]).abs() <= 2.0 * e.std_uncertainty {
                    inside[j] += 1;
                }
            }
        }
        assert!(
            id.chi2 / (id.dof as f64) < 1.6,
            "χ²/dof = {}",
            id.chi2 / id.dof as f64
        );
    }
    let report: Vec<String> = (0..set.len())
        .filter(|&j| counted[j] > 0)
        .map(|j| format!("{} {}/{}", set.params[j].name(), inside[j], counted[j]))
        .collect();
    let total_in: usize = inside.iter().sum();
    let total: usize = counted.iter().sum();
    // Overall ≥ 90 % (95.4 % expected); each parameter ≥ 85 % (with ~10 parameters, one of them
    // falling to 89 by chance has ~10 % probability, to 85 well under 1e-3).
    assert!(total_in as f64 >= 0.9 * total as f64, "{report:?}");
    for j in 0..set.len() {
        if counted[j] > 0 {
            assert_eq!(counted[j], 100);
            assert!(inside[j] >= 85, "{report:?}");
        }
    }
    eprintln!("coverage at 2u: {report:?}");
}

#[test]
fn with_c_fixed_the_c_location_errors_are_named_unidentifiable() {
    let g = trunnion();
    let set = ParameterSet::location_and_assembly(&g);
    let mut rng = Rng(3);
    let obs = observe(
        &set,
        &vec![0.0; set.len()],
        &spread(50, Some(30.0)),
        1.25e-4,
        &mut rng,
    );
    let id = identify(&g, &set, &obs, &IdentifyOptions::default()).unwrap();
    let text: Vec<&str> = id.relations.iter().map(|r| r.message.as_str()).collect();
    for name in ["E_X0C", "E_Y0C", "E_A0C", "E_B0C", "E_C0C"] {
        let e = id.estimates.iter().find(|e| e.name == name).unwrap();
        assert_ne!(e.status, Status::Identified, "{name}");
        assert!(
            text.iter().any(|t| t.contains(name)),
            "{name} not named in {text:#?}"
        );
    }
}

#[test]
fn too_few_configurations_are_refused_with_the_counts() {
    let g = trunnion();
    let set = ParameterSet::location_and_assembly(&g);
    let mut rng = Rng(1);
    let obs = observe(
        &set,
        &vec![0.0; set.len()],
        &spread(6, None),
        1.25e-4,
        &mut rng,
    );
    let e = identify(&g, &set, &obs, &IdentifyOptions::default()).unwrap_err();
    assert_eq!(e.to_string(), "too few configurations: 6 configurations give 18 readings for 19 parameters (need at least 8 configurations)");
}

#[test]
fn a_d_optimal_half_is_nearly_as_good_as_all_candidates() {
    let g = trunnion();
    let set = ParameterSet::location_and_assembly(&g);
    let mut rng = Rng(9);
    let cands = observe(
        &set,
        &vec![0.0; set.len()],
        &spread(200, None),
        1.25e-4,
        &mut rng,
    );
    let d = crate::design::d_optimal(&g, &set, &cands, 25).unwrap();
    assert_eq!(d.chosen.len(), 25);
    let again = crate::design::d_optimal(&g, &set, &cands, 25).unwrap();
    assert_eq!(d, again);
    // 25 chosen versus 25 spread ones (every 8th): the chosen have the larger determinant.
    let spread25: Vec<Observation> = cands.iter().step_by(8).copied().collect();
    let chosen: Vec<Observation> = d.chosen.iter().map(|&i| cands[i]).collect();
    let worst_u = |obs: &[Observation]| {
        let id = identify(
            &g,
            &set,
            obs,
            &IdentifyOptions {
                refine_steps: 0,
                ..Default::default()
            },
        )
        .unwrap();
        id.estimates
            .iter()
            .filter(|e| e.status != Status::Fixed)
            .map(|e| e.std_uncertainty / if e.is_angle { 1e-3 } else { 1.0 })
            .fold(0.0, f64::max)
    };
    assert!(
        worst_u(&chosen) < worst_u(&spread25),
        "{} vs {}",
        worst_u(&chosen),
        worst_u(&spread25)
    );
}

#[test]
fn a_second_sphere_separates_the_zero_offset_of_c_from_the_datum_offset() {
    let g = trunnion();
    let set = ParameterSet::location_and_assembly(&g);
    let mut rng = Rng(17);
    let zeros = vec![0.0; set.len()];
    let configs = spread(50, None);
    let one = observe(&set, &zeros, &configs, 1.25e-4, &mut rng);
    let id1 = identify(&g, &set, &one, &IdentifyOptions::default()).unwrap();
    assert!(
        id1.relations
            .iter()
            .any(|r| r.fixed == "E_YW" && r.message.contains("E_C0C")),
        "{:#?}",
        id1.relations
    );
    // Every other configuration on a second sphere 250 mm away, 50 mm lower.
    let target = [-250.0, 80.0, -50.0];
    let two: Vec<Observation> = one
        .iter()
        .enumerate()
        .map(|(i, o)| {
            if i % 2 == 0 {
                return *o;
            }
            let q = linear_axes_for(&g, o.rotary_deg, Vector3::from(target), &|_: &Pose| {
                ErrorState::default()
            })
            .unwrap();
            Observation {
                target_w_mm: target,
                nominal_mm: q,
                measured_mm: q,
                ..*o
            }
        })
        .collect();
    let id2 = identify(&g, &set, &two, &IdentifyOptions::default()).unwrap();
    assert_eq!(id2.rank, id1.rank + 1);
    for name in ["E_C0C", "E_YW"] {
        let e = id2.estimates.iter().find(|e| e.name == name).unwrap();
        assert_eq!(e.status, Status::Identified, "{name}");
    }
}

#[test]
fn a_relocated_sphere_s_unknown_offset_is_fitted_beside_the_machine_s_errors() {
    let g = trunnion();
    let set = ParameterSet::location_and_assembly(&g).with_motion_harmonics(&g, 2);
    let mut rng = Rng(5);
    let values = truth(&set, &mut rng);
    let configs = spread(60, None);
    let datum = observe(&set, &values, &configs, 0.0, &mut rng);
    // A third of the configurations probe the artefact's second sphere (its offset from the
    // datum calibrated), a third a sphere put at (−200, 150, 120) mm, really 0.3 mm away.
    // (Without the calibrated pair, the zero offset of C could not be told from the relocated
    // sphere's tangential offset.)
    let (target, offset) = ([-200.0, 150.0, 120.0], Vector3::new(0.3, -0.2, 0.1));
    let obs: Vec<Observation> = datum
        .iter()
        .enumerate()
        .map(|(i, o)| {
            let (target, real, placement) = match i % 3 {
                0 => return *o,
                1 => ([-250.0, 80.0, -50.0], Vector3::new(-250.0, 80.0, -50.0), 0),
                _ => (target, Vector3::from(target) + offset, 1),
            };
            let q = linear_axes_for(&g, o.rotary_deg, real, &|pose: &Pose| {
                set.state_at(&values, pose)
            })
            .unwrap();
            Observation {
                target_w_mm: target,
                nominal_mm: nominal_linear_axes(&g, o.rotary_deg, Vector3::from(target)),
                measured_mm: q,
                placement,
                ..*o
            }
        })
        .collect();
    assert_eq!(placements_in(&obs), 1);
    let with = set.clone().with_placements(1);
    let id = identify(&g, &with, &obs, &IdentifyOptions::default()).unwrap();
    let got = with.placement_offset_mm(&id.values(), 1);
    for k in 0..3 {
        assert!((got[k] - offset[k]).abs() < 1e-7, "{got:?}");
    }
    assert!(id.rms_residual_mm < 1e-8, "{}", id.rms_residual_mm);
    // Ignoring the offset (the sphere taken where it was put) leaves it in the residual.
    let without = identify(&g, &set, &obs, &IdentifyOptions::default()).unwrap();
    assert!(
        without.rms_residual_mm > 1e-3,
        "{}",
        without.rms_residual_mm
    );
    // The offset never enters a compensation.
    let pose = Pose {
        linear_mm: [0.0; 3],
        rotary_deg: [30.0, -20.0],
    };
    let n = set.len();
    assert_eq!(
        with.state_at(&id.values(), &pose),
        set.state_at(&id.values()[..n], &pose)
    );
}
