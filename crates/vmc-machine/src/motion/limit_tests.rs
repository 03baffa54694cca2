//! Tests of the machine's motion limits: parsing, defaults, validation.

use super::*;

#[test]
fn limits_parse_from_toml_with_their_defaults_and_round_trip() {
    let text = "rapid_mm_per_min = [30000.0, 30000.0, 24000.0]\n\
                max_feed_mm_per_min = 10000.0\n\
                max_accel_mm_per_s2 = [2000.0, 2000.0, 1500.0]\n";
    let limits: MotionLimits = toml::from_str(text).expect("valid limits");
    // The optional fields left out take the built-in defaults.
    let built_in = MotionLimits::default();
    assert_eq!(limits.tool_change_s, built_in.tool_change_s);
    assert_eq!(limits.max_spindle_rpm, built_in.max_spindle_rpm);
    assert!(limits.validate().is_ok());
    // What is written reads back as the same limits.
    let text = toml::to_string(&limits).unwrap();
    assert_eq!(toml::from_str::<MotionLimits>(&text).unwrap(), limits);
}

#[test]
fn unknown_limit_field_is_rejected() {
    let text = "rapid_mm_per_min = [1.0, 1.0, 1.0]\nmax_feed_mm_per_min = 1.0\n\
                max_accel_mm_per_s2 = [1.0, 1.0, 1.0]\njerk = 3.0\n";
    assert!(toml::from_str::<MotionLimits>(text).is_err());
}

#[test]
fn validate_names_the_bad_axis_field() {
    let mut limits = MotionLimits::default();
    limits.max_accel_mm_per_s2[1] = 0.0;
    match limits.validate() {
        Err(MotionError::InvalidLimit { field, .. }) => {
            assert_eq!(field, "max_accel_mm_per_s2[1]")
        }
        other => panic!("expected InvalidLimit, got {other:?}"),
    }
    let limits = MotionLimits {
        tool_change_s: f64::NAN,
        ..MotionLimits::default()
    };
    assert!(matches!(
        limits.validate(),
        Err(MotionError::InvalidLimit { field, .. }) if field == "tool_change_s"
    ));
}
