//! Physical plausibility of every number in a machine file, checked in one pass over the parsed
//! TOML before the description is built (three- and five-axis files alike).
//!
//! Each numeric field is matched by its name: an exact name (`efficiency`), then the longest
//! unit suffix of the project's naming convention (`_degc`, `_mm`, `_w_per_k`, `_n_m`, …, see
//! [`RANGES`]); fields given in the unit of their table (`poly`, `amplitude`, `value`, … of an
//! error with `unit = "um"` or `"urad"`) take that unit's range; `points = [[time_s,
//! temp_degc], …]` of an ambient table are checked as a time and a temperature; any other
//! number must stay within ±[`UNITLESS_LIMIT`]. No number escapes: a field added later without
//! a rule gets the catch-all bound, and non-finite numbers are refused everywhere.
//!
//! The ranges are wide: they refuse what no machine tool can have (an ambient of 10⁶ °C, a
//! motor torque of 4·10¹² N·m, a polynomial coefficient of 10³⁰⁰ µm), not what is unusual.
//! Finer rules (signs, orderings, references between fields) stay with the sections' own
//! checks.

/// A plausible range for the fields whose name ends in `_{suffix}` (or is `suffix`).
#[derive(Debug, Clone, Copy)]
pub struct Range {
    /// The unit suffix of the field name, without the leading `_`.
    pub suffix: &'static str,
    /// Smallest plausible value.
    pub min: f64,
    /// Largest plausible value.
    pub max: f64,
    /// What the quantity is, with its unit (for messages and docs).
    pub what: &'static str,
}

const fn r(suffix: &'static str, min: f64, max: f64, what: &'static str) -> Range {
    Range {
        suffix,
        min,
        max,
        what,
    }
}

/// The plausible range of each unit suffix (docs/file-formats.md lists them).
pub const RANGES: &[Range] = &[
    r("degc", -60.0, 250.0, "a temperature, °C"),
    r("s", 0.0, 1e8, "a time, s (3 years)"),
    r("mm", -1e5, 1e5, "a length, mm (±100 m)"),
    r("um", -1e5, 1e5, "a length, µm (±0.1 m)"),
    r("um2", 0.0, 1e10, "a squared length, µm²"),
    r("urad", -1e5, 1e5, "an angle, µrad (±0.1 rad)"),
    r("rad", -1e3, 1e3, "an angle, rad"),
    r("deg", -1e5, 1e5, "an angle, degrees"),
    r("mm_per_min", 0.0, 1e7, "a feed, mm/min"),
    r("mm_per_s2", 0.0, 1e7, "an acceleration, mm/s²"),
    r("deg_per_s", 0.0, 1e6, "an angular speed, °/s"),
    r("deg_per_s2", 0.0, 1e7, "an angular acceleration, °/s²"),
    r("rpm", 0.0, 2e5, "a spindle speed, rpm"),
    r("w", -1e6, 1e6, "a power, W"),
    r("w_per_k", 0.0, 1e6, "a conductance, W/K"),
    r("j_per_k", 0.0, 1e10, "a heat capacity, J/K"),
    r("per_krpm", -1e3, 1e3, "a gain per 1000 rpm"),
    r("n_m", -1e5, 1e5, "a torque, N·m"),
    r("n_mm", -1e8, 1e8, "a torque, N·mm"),
    r("n", -1e8, 1e8, "a force, N"),
    r("um_per_k", -1e4, 1e4, "a thermal gain, µm/K"),
    r("um_per_k_m", -1e4, 1e4, "a thermal gain, µm/(K·m)"),
    r("urad_per_k", -1e4, 1e4, "a thermal gain, µrad/K"),
    r("um_per_m", 0.0, 1e4, "a length per length, µm/m"),
    r("hz", 0.0, 1e7, "a frequency, Hz"),
    r("kg", 0.0, 1e6, "a mass, kg"),
];

/// Bound of a number whose name carries no unit (weights, counts, orders), ±.
pub const UNITLESS_LIMIT: f64 = 1e6;

/// Range of the fields given in their table's `unit` (`um` or `urad`): ±10 mm or ±10 mrad
/// (an error coefficient of more than that is not a machine tool's).
const IN_TABLE_UNIT: f64 = 1e4;

/// Fields whose values are in the unit named by their table's `unit` field.
const TABLE_UNIT_FIELDS: [&str; 5] = [
    "poly",
    "amplitude",
    "random_sigma",
    "fine_amplitude",
    "value",
];

/// A number outside its plausible range: the dotted field and the message.
#[derive(Debug, Clone, PartialEq)]
pub struct Implausible {
    /// Dotted path of the field, e.g. `thermal.nodes[3].capacity_j_per_k`.
    pub field: String,
    /// What is wrong, with the range.
    pub msg: String,
}

/// Checks every number of a parsed machine file.
///
/// # Errors
/// The first number outside its plausible range, or not finite.
pub fn check_table(table: &toml::Table) -> Result<(), Implausible> {
    walk_table(table, "")
}

fn walk_table(table: &toml::Table, prefix: &str) -> Result<(), Implausible> {
    let unit = table.get("unit").and_then(|u| u.as_str());
    let is_ambient_table = table.get("kind").and_then(|k| k.as_str()) == Some("table");
    for (key, value) in table {
        let field = if prefix.is_empty() {
            key.clone()
        } else {
            format!("{prefix}.{key}")
        };
        if is_ambient_table && key == "points" {
            check_points(value, &field)?;
            continue;
        }
        let rule = rule_for(key, unit);
        walk_value(value, &field, &rule)?;
    }
    Ok(())
}

/// The range a field's numbers must lie in: `(min, max, what)`.
fn rule_for(key: &str, unit: Option<&str>) -> (f64, f64, String) {
    if key == "efficiency" {
        return (0.0, 1.0, "an efficiency (0 to 1)".to_string());
    }
    if TABLE_UNIT_FIELDS.contains(&key) {
        if let Some(u @ ("um" | "urad")) = unit {
            return (
                -IN_TABLE_UNIT,
                IN_TABLE_UNIT,
                format!("an error term in {u}"),
            );
        }
    }
    let best = RANGES
        .iter()
        .filter(|r| key == r.suffix || key.ends_with(&format!("_{}", r.suffix)))
        .max_by_key(|r| r.suffix.len());
    match best {
        Some(r) => (r.min, r.max, r.what.to_string()),
        None => (
            -UNITLESS_LIMIT,
            UNITLESS_LIMIT,
            "a number without a unit in its name".to_string(),
        ),
    }
}

fn walk_value(
    value: &toml::Value,
    field: &str,
    rule: &(f64, f64, String),
) -> Result<(), Implausible> {
    match value {
        toml::Value::Integer(i) => check_number(*i as f64, field, rule),
        toml::Value::Float(v) => check_number(*v, field, rule),
        toml::Value::Array(items) => {
            for (i, item) in items.iter().enumerate() {
                walk_value(item, &format!("{field}[{i}]"), rule)?;
            }
            Ok(())
        }
        toml::Value::Table(t) => walk_table(t, field),
        _ => Ok(()),
    }
}

fn check_number(
    v: f64,
    field: &str,
    (min, max, what): &(f64, f64, String),
) -> Result<(), Implausible> {
    if v.is_finite() && v >= *min && v <= *max {
        return Ok(());
    }
    Err(Implausible {
        field: field.to_string(),
        msg: format!(
            "{} is not plausible for {what}: the range is [{}, {}]",
            short(v),
            short(*min),
            short(*max)
        ),
    })
}

/// A number as written by a person: plain when moderate, else in exponent form.
fn short(v: f64) -> String {
    if v == 0.0 || (1e-3..1e4).contains(&v.abs()) {
        format!("{v}")
    } else {
        format!("{v:e}")
    }
}

/// `[[time_s, temp_degc], …]` of an ambient table.
fn check_points(value: &toml::Value, field: &str) -> Result<(), Implausible> {
    let time = rule_for("time_s", None);
    let temp = rule_for("temp_degc", None);
    let Some(points) = value.as_array() else {
        return Ok(());
    };
    for (i, p) in points.iter().enumerate() {
        let Some(pair) = p.as_array() else { continue };
        for (j, v) in pair.iter().enumerate() {
            let rule = if j == 0 { &time } else { &temp };
            walk_value(v, &format!("{field}[{i}][{j}]"), rule)?;
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn check(text: &str) -> Result<(), Implausible> {
        check_table(&text.parse::<toml::Table>().unwrap())
    }

    #[test]
    fn the_shipped_machine_files_are_plausible() {
        for text in [
            include_str!("../../../machines/vmc-reference.toml"),
            include_str!("../../../machines/trunnion-ac.toml"),
        ] {
            check(text).unwrap();
        }
    }

    #[test]
    fn an_absurd_value_is_named_by_its_dotted_field_and_its_range() {
        let e = check("[thermal]\nambient = { kind = \"constant\", temp_degc = 1e6 }").unwrap_err();
        assert_eq!(e.field, "thermal.ambient.temp_degc");
        assert!(e.msg.contains("a temperature"), "{}", e.msg);
        let e = check("[thermal]\nsources = [{ torque_n_m = 4e12 }]").unwrap_err();
        assert_eq!(e.field, "thermal.sources[0].torque_n_m");
        let e = check("[errors.motion.EXX]\nunit = \"um\"\npoly = [0.0, -15e300]").unwrap_err();
        assert_eq!(e.field, "errors.motion.EXX.poly[1]");
        assert!(check("[thermal]\nambient = { kind = \"constant\", temp_degc = -300 }").is_err());
    }

    #[test]
    fn the_longest_unit_suffix_decides() {
        // µm/(K·m) may be negative, a length per length (`_um_per_m`) may not.
        assert!(check("gain_um_per_k_m = -5.0").is_ok());
        assert!(check("laser_noise_um_per_m = -5.0").is_err());
        assert!(check("torque_per_krpm_n_m = 0.05").is_ok());
    }

    #[test]
    fn ambient_table_points_are_a_time_and_a_temperature() {
        let ok = "[a]\nkind = \"table\"\npoints = [[0.0, 20.0], [3600.0, 22.0]]";
        assert!(check(ok).is_ok());
        let e =
            check("[a]\nkind = \"table\"\npoints = [[0.0, 20.0], [3600.0, 2000.0]]").unwrap_err();
        assert_eq!(e.field, "a.points[1][1]");
    }

    #[test]
    fn a_number_without_a_rule_still_has_a_bound() {
        assert!(check("weight = 3.0").is_ok());
        assert!(check("weight = 1e9").is_err());
    }
}
