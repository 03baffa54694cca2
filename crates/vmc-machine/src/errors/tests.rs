use super::*;

const NODES: &[&str] = &[
    "x_screw_0",
    "x_screw_1",
    "x_screw_2",
    "x_screw_3",
    "x_screw_4",
    "y_screw_0",
    "y_screw_1",
    "y_screw_2",
    "y_screw_3",
    "z_screw_0",
    "z_screw_1",
    "z_screw_2",
    "z_screw_3",
    "bed_top",
    "bed_bottom",
    "column_top_front",
    "column_mid_front",
    "column_top_back",
    "column_mid_back",
    "headstock_left",
    "headstock_right",
    "headstock_front",
    "headstock_back",
    "saddle",
    "spindle_housing",
    "spindle_front_bearing",
];

fn node_index(name: &str) -> Option<usize> {
    NODES.iter().position(|n| *n == name)
}

fn reference_spec() -> ErrorFieldSpec {
    #[derive(serde::Deserialize)]
    struct Wrap {
        errors: ErrorFieldSpec,
    }
    let text = include_str!("../../../../machines/vmc-reference.toml");
    toml::from_str::<Wrap>(text)
        .expect("reference error field parses")
        .errors
}

const MIN: [f64; 3] = [0.0, 0.0, -450.0];
const MAX: [f64; 3] = [560.0, 400.0, 0.0];

fn field(spec: &ErrorFieldSpec, seed: u64) -> ErrorField {
    ErrorField::new(spec, MIN, MAX, &node_index, seed).expect("valid field")
}

/// 1″ in µrad.
const ARCSEC_URAD: f64 = 4.848;

/// The study's machine, whose size the reference machine follows: positioning errors over the
/// travel of about 20 / 27 / 35 µm in X / Y / Z, straightness errors of 1–3 µm, angular motion
/// errors of 1–4″ and squareness errors of tens of µrad. Evaluated through the field (profiles,
/// seeded parts, µm → mm and µrad → rad) at 20 °C for three seeds.
#[test]
fn the_reference_error_field_has_the_sizes_the_study_reports() {
    let spec = reference_spec();
    spec.validate(&|n| node_index(n).is_some()).unwrap();
    let temps = vec![20.0; NODES.len()];
    let study_positioning_um = [20.0, 27.0, 35.0];
    for seed in [1, 2, 3] {
        let f = field(&spec, seed);
        for axis in 0..3 {
            // Peak-to-peak (µm) of each translation and largest |angle| (µrad) over 1 mm steps.
            let (mut lo, mut hi, mut angle) = ([f64::MAX; 3], [f64::MIN; 3], [0.0f64; 3]);
            let steps = (MAX[axis] - MIN[axis]).round() as usize;
            for i in 0..=steps {
                let pos = MIN[axis] + (MAX[axis] - MIN[axis]) * i as f64 / steps as f64;
                let e = f.axis_errors(axis, pos, &temps);
                for c in 0..3 {
                    lo[c] = lo[c].min(e.lin_mm[c] * 1e3);
                    hi[c] = hi[c].max(e.lin_mm[c] * 1e3);
                    angle[c] = angle[c].max(e.ang_rad[c].abs() * 1e6);
                }
            }
            let what = format!("seed {seed}, axis {axis}");
            for c in 0..3 {
                let span_um = hi[c] - lo[c];
                if c == axis {
                    // Positioning: within ±50 % of the study's figure.
                    let study = study_positioning_um[axis];
                    assert!(
                        (0.5 * study..=1.5 * study).contains(&span_um),
                        "{what}: positioning spans {span_um:.2} µm"
                    );
                } else {
                    // Straightness: 1–3 µm, with room for the seeded part (σ 0.4 µm).
                    assert!(
                        (0.5..=5.0).contains(&span_um),
                        "{what}: straightness {c} spans {span_um:.2} µm"
                    );
                }
                assert!(
                    angle[c] <= 4.0 * ARCSEC_URAD,
                    "{what}: angle {c} reaches {:.2} µrad",
                    angle[c]
                );
            }
            let largest = angle.iter().copied().fold(0.0, f64::max);
            assert!(
                largest >= ARCSEC_URAD,
                "{what}: no angle reaches 1″: {angle:?}"
            );
        }
        let sq = f.elementary([280.0, 200.0, -225.0], &temps).squareness;
        let sq_urad = [sq.xy_rad, sq.xz_rad, sq.yz_rad].map(|a| a.abs() * 1e6);
        let largest = sq_urad.iter().copied().fold(0.0, f64::max);
        assert!(
            (10.0..100.0).contains(&largest),
            "seed {seed}: squareness {sq_urad:?} µrad"
        );
    }
}

#[test]
fn same_seed_gives_identical_bits_and_another_seed_differs() {
    let spec = reference_spec();
    let temps = vec![20.0; NODES.len()];
    let a = field(&spec, 7).elementary([123.0, 234.0, -345.0], &temps);
    let b = field(&spec, 7).elementary([123.0, 234.0, -345.0], &temps);
    let c = field(&spec, 8).elementary([123.0, 234.0, -345.0], &temps);
    assert_eq!(a, b);
    assert_ne!(a.axes[0].lin_mm[0], c.axes[0].lin_mm[0]);
}

#[test]
fn at_reference_temperature_thermal_terms_vanish() {
    // Removing every thermal term must not change the errors at 20 °C everywhere.
    let spec = reference_spec();
    let mut cold = spec.clone();
    for p in cold.motion.values_mut() {
        p.thermal.clear();
    }
    for c in cold
        .squareness
        .values_mut()
        .chain(cold.spindle.values_mut())
    {
        c.thermal.clear();
    }
    let temps = vec![20.0; NODES.len()];
    let pos = [300.0, 100.0, -200.0];
    assert_eq!(
        field(&spec, 3).elementary(pos, &temps),
        field(&cold, 3).elementary(pos, &temps)
    );
    // And at another temperature they do not vanish.
    let warm = vec![25.0; NODES.len()];
    assert_ne!(
        field(&spec, 3).elementary(pos, &warm),
        field(&cold, 3).elementary(pos, &warm)
    );
}

#[test]
fn uniform_screw_warming_gives_linear_expansion_from_the_fixed_end() {
    // Only thermal parts: zero all static parts.
    let mut spec = reference_spec();
    for p in spec.motion.values_mut() {
        p.poly.clear();
        p.harmonics.clear();
        p.random_sigma = 0.0;
        p.fine_amplitude = 0.0;
    }
    let f = field(&spec, 1);
    let mut temps = vec![20.0; NODES.len()];
    for n in [
        "x_screw_0",
        "x_screw_1",
        "x_screw_2",
        "x_screw_3",
        "x_screw_4",
    ] {
        temps[node_index(n).unwrap()] = 21.0;
    }
    for n in ["z_screw_0", "z_screw_1", "z_screw_2", "z_screw_3"] {
        temps[node_index(n).unwrap()] = 22.0;
    }
    // X: 1.5 µm/(K·m) · 1 K · 0.560 m = 0.84 µm at the far end, half of it at mid-travel.
    let at_end = f.axis_errors(0, 560.0, &temps).lin_mm[0];
    let at_mid = f.axis_errors(0, 280.0, &temps).lin_mm[0];
    assert!((at_end - 0.84e-3).abs() < 1e-9, "{at_end}");
    assert!((at_mid - 0.42e-3).abs() < 1e-9, "{at_mid}");
    // Z is fixed at the top (max): at the bottom the nut is 450 mm away:
    // −1 µm/(K·m) · 2 K · 0.450 m = −0.9 µm; at the top 0.
    let bottom = f.axis_errors(2, -450.0, &temps).lin_mm[2];
    let top = f.axis_errors(2, 0.0, &temps).lin_mm[2];
    assert!((bottom + 0.9e-3).abs() < 1e-9, "{bottom}");
    assert!(top.abs() < 1e-12, "{top}");
}

#[test]
fn only_the_heated_segment_under_the_span_contributes() {
    let mut spec = reference_spec();
    for p in spec.motion.values_mut() {
        p.poly.clear();
        p.harmonics.clear();
        p.random_sigma = 0.0;
        p.fine_amplitude = 0.0;
    }
    let f = field(&spec, 1);
    let mut temps = vec![20.0; NODES.len()];
    temps[node_index("x_screw_4").unwrap()] = 30.0; // the last 112 mm of the screw
    assert_eq!(f.axis_errors(0, 400.0, &temps).lin_mm[0], 0.0);
    // 1.5e-3 µm/(K·mm) · 10 K · (500 − 448) mm = 0.78 µm.
    let v = f.axis_errors(0, 500.0, &temps).lin_mm[0];
    assert!((v - 0.78e-3).abs() < 1e-9, "{v}");
}

#[test]
fn catmull_rom_spline_passes_through_its_knots() {
    let knots = [0.0, 1.0, -2.0, 0.5, 3.0];
    for (k, v) in knots.iter().enumerate() {
        let u = k as f64 / 4.0;
        assert!((catmull_rom(&knots, u) - v).abs() < 1e-12);
    }
}

#[test]
fn an_angular_error_written_in_um_is_rejected_naming_the_field() {
    let mut spec = reference_spec();
    spec.motion.get_mut("EBX").unwrap().unit = spec::ValueUnit::Um;
    let err = spec.validate(&|n| node_index(n).is_some()).unwrap_err();
    assert_eq!(
        err.to_string(),
        "errors.motion.EBX.unit: must be \"urad\" for this error"
    );
}

#[test]
fn an_unknown_node_and_a_missing_error_are_named() {
    let mut spec = reference_spec();
    spec.motion.get_mut("EXX").unwrap().thermal[0].nodes[2] = "x_scru_2".into();
    let err = spec.validate(&|n| node_index(n).is_some()).unwrap_err();
    assert_eq!(
        err.to_string(),
        "errors.motion.EXX.thermal[0].nodes[2]: unknown thermal node \"x_scru_2\""
    );
    let mut spec = reference_spec();
    spec.motion.remove("ECY");
    let err = spec.validate(&|n| node_index(n).is_some()).unwrap_err();
    assert_eq!(err.to_string(), "errors.motion.ECY: missing");
}

#[test]
fn each_thermal_gain_is_named_in_its_unit() {
    // A pitch (µrad) given a µm gain, a screw given a plain µm/K gain, a missing gain.
    let mut spec = reference_spec();
    let t = &mut spec.motion.get_mut("EAZ").unwrap().thermal[0];
    t.gain_um_per_k = t.gain_urad_per_k.take();
    let err = spec.validate(&|n| node_index(n).is_some()).unwrap_err();
    assert_eq!(
        err.to_string(),
        "errors.motion.EAZ.thermal[0].gain_um_per_k: this term's gain is `gain_urad_per_k` \
         (its shape and its error's unit)"
    );
    let mut spec = reference_spec();
    let t = &mut spec.motion.get_mut("EXX").unwrap().thermal[0];
    t.gain_um_per_k = t.gain_um_per_k_m.take();
    let err = spec.validate(&|n| node_index(n).is_some()).unwrap_err();
    assert!(
        err.to_string().starts_with(
            "errors.motion.EXX.thermal[0].gain_um_per_k: this term's gain is `gain_um_per_k_m`"
        ),
        "{err}"
    );
    let mut spec = reference_spec();
    spec.motion.get_mut("EXX").unwrap().thermal[0].gain_um_per_k_m = None;
    let err = spec.validate(&|n| node_index(n).is_some()).unwrap_err();
    assert_eq!(
        err.to_string(),
        "errors.motion.EXX.thermal[0].gain_um_per_k_m: missing"
    );
}

#[test]
fn reversal_flips_with_direction_and_repeatability_is_seeded() {
    let spec = reference_spec();
    let mut a = ApproachErrors::new(&spec, 5);
    a.note_motion([1.0, 1.0, 1.0]);
    assert_eq!(a.reversal_mm(), [0.25e-3, 0.3e-3, 0.25e-3]);
    a.note_motion([-1.0, 0.0, -2.0]);
    assert_eq!(a.reversal_mm(), [-0.25e-3, 0.3e-3, -0.25e-3]);
    let mut b = ApproachErrors::new(&spec, 5);
    b.note_motion([-1.0, 0.0, -2.0]);
    assert_eq!(a.positioning_mm(), b.positioning_mm());
}
