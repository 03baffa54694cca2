//! The app side of the milling-dynamics study: the tool file (TOML) that gives a cutter and the
//! modes of its tool tip (read and checked; written from fitted modes by [`tool_file_toml`]),
//! the lobes table (CSV) and the time series of one cut (CSV). The numerics are the
//! `vmc-dynamics` crate (re-exported as [`vmc_dynamics`]); this module only reads, checks and
//! writes text.
//!
//! A tool file (units in names; every field checked, unknown fields refused):
//!
//! ```toml
//! name = "my cutter"                # optional
//! [tool]
//! teeth = 2
//! diameter_mm = 16.0
//! helix_deg = 0.0                   # optional, in [0, 90); 0 = straight teeth
//! kt_n_per_m2 = 6.0e8               # tangential specific cutting force
//! kn_n_per_m2 = 2.0e8               # normal (radial) specific cutting force
//! kte_n_per_m = 0.0                 # optional edge coefficients
//! kne_n_per_m = 0.0
//! process_damping_n_per_m = 0.0     # optional
//! [[modes.x]]                       # modes at the tool tip in x (feed), then [[modes.y]]
//! frequency_hz = 922.0
//! damping_ratio = 0.011
//! modal_mass_kg = 0.03993           # or stiffness_n_per_m
//! ```

use std::fmt::Write as _;
use std::path::Path;

use serde::Deserialize;
use thiserror::Error;

use crate::read;
use vmc_dynamics::{DynamicsError, LobePoint, Mode, TipModes, Tool};

/// The benchmark tool shipped with the repository, used when no tool file is given.
pub const DEFAULT_TOOL_TOML: &str =
    include_str!("../../../machines/benchmarks/insperger-1dof.toml");
/// Where [`DEFAULT_TOOL_TOML`] lives in the repository.
pub const DEFAULT_TOOL_PATH: &str = "machines/benchmarks/insperger-1dof.toml";

/// A tool file that cannot be used.
#[derive(Debug, Error)]
pub enum ToolFileError {
    /// The file could not be read.
    #[error(transparent)]
    Read(#[from] read::ReadError),
    /// Not TOML, or not the schema (the parser's message has line and column).
    #[error("{path}: {msg}")]
    Parse {
        /// The file.
        path: String,
        /// The TOML parser's message.
        msg: String,
    },
    /// A mode gives neither or both of its stiffness and its modal mass.
    #[error("{path}: modes.{direction}[{index}]: give exactly one of stiffness_n_per_m and modal_mass_kg")]
    ModeSize {
        /// The file.
        path: String,
        /// `x` or `y`.
        direction: &'static str,
        /// Index of the mode in its list.
        index: usize,
    },
    /// A value the dynamics refuses (no teeth, a negative damping ratio, …).
    #[error("{path}: {err}")]
    Invalid {
        /// The file.
        path: String,
        /// What is wrong.
        err: DynamicsError,
    },
}

/// A cutter and the modes of its tool tip, as read from a tool file.
#[derive(Debug, Clone, PartialEq)]
pub struct ToolDynamics {
    /// The file's `name` (or the file name).
    pub name: String,
    /// The cutter.
    pub tool: Tool,
    /// The tool-tip modes.
    pub modes: TipModes,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ToolFile {
    name: Option<String>,
    tool: ToolSection,
    #[serde(default)]
    modes: ModesSection,
}

/// The `[tool]` table of a tool file (also of a blade file).
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct ToolSection {
    teeth: u32,
    diameter_mm: f64,
    #[serde(default)]
    helix_deg: f64,
    kt_n_per_m2: f64,
    kn_n_per_m2: f64,
    #[serde(default)]
    kte_n_per_m: f64,
    #[serde(default)]
    kne_n_per_m: f64,
    #[serde(default)]
    process_damping_n_per_m: f64,
}

#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct ModesSection {
    #[serde(default)]
    x: Vec<ModeSpec>,
    #[serde(default)]
    y: Vec<ModeSpec>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ModeSpec {
    frequency_hz: f64,
    damping_ratio: f64,
    stiffness_n_per_m: Option<f64>,
    modal_mass_kg: Option<f64>,
}

impl ToolSection {
    /// The cutter (not yet validated).
    pub(crate) fn to_tool(&self) -> Tool {
        Tool {
            teeth: self.teeth,
            diameter_mm: self.diameter_mm,
            helix_deg: self.helix_deg,
            kt_n_per_m2: self.kt_n_per_m2,
            kn_n_per_m2: self.kn_n_per_m2,
            kte_n_per_m: self.kte_n_per_m,
            kne_n_per_m: self.kne_n_per_m,
            process_damping_n_per_m: self.process_damping_n_per_m,
        }
    }
}

impl ToolDynamics {
    /// Reads and checks a tool file.
    ///
    /// # Errors
    /// See [`ToolFileError`].
    pub fn load(path: &Path) -> Result<Self, ToolFileError> {
        let text = read::read_named(path, "tool file")?;
        Self::from_toml_str(&text, &path.display().to_string())
    }

    /// The tool of a `--tool FILE` option (the benchmark tool without one), with where it came
    /// from, for the report.
    ///
    /// # Errors
    /// See [`ToolFileError`].
    pub fn from_option(path: Option<&Path>) -> Result<(Self, String), ToolFileError> {
        Ok(match path {
            Some(path) => (Self::load(path)?, path.display().to_string()),
            None => (Self::benchmark(), DEFAULT_TOOL_PATH.to_string()),
        })
    }

    /// The benchmark tool shipped with the repository ([`DEFAULT_TOOL_PATH`]).
    pub fn benchmark() -> Self {
        // The embedded file is checked by a test.
        Self::from_toml_str(DEFAULT_TOOL_TOML, DEFAULT_TOOL_PATH)
            .unwrap_or_else(|e| unreachable!("the embedded benchmark tool is valid: {e}"))
    }

    /// Parses and checks a tool file's text; `path` names it in errors.
    ///
    /// # Errors
    /// See [`ToolFileError`].
    pub fn from_toml_str(text: &str, path: &str) -> Result<Self, ToolFileError> {
        let f: ToolFile = toml::from_str(text).map_err(|e| ToolFileError::Parse {
            path: path.to_string(),
            msg: crate::read::one_line_toml_error(&e),
        })?;
        let tool = f.tool.to_tool();
        let modes_of = |specs: Vec<ModeSpec>, direction| {
            specs
                .into_iter()
                .enumerate()
                .map(|(index, m)| match (m.stiffness_n_per_m, m.modal_mass_kg) {
                    (Some(k), None) => Ok(Mode {
                        frequency_hz: m.frequency_hz,
                        damping_ratio: m.damping_ratio,
                        stiffness_n_per_m: k,
                    }),
                    (None, Some(mass)) => {
                        Ok(Mode::from_mass(m.frequency_hz, m.damping_ratio, mass))
                    }
                    _ => Err(ToolFileError::ModeSize {
                        path: path.to_string(),
                        direction,
                        index,
                    }),
                })
                .collect::<Result<Vec<_>, _>>()
        };
        let modes = TipModes {
            x: modes_of(f.modes.x, "x")?,
            y: modes_of(f.modes.y, "y")?,
        };
        let invalid = |err| ToolFileError::Invalid {
            path: path.to_string(),
            err,
        };
        tool.validate().map_err(invalid)?;
        modes.validate().map_err(invalid)?;
        Ok(Self {
            name: f.name.unwrap_or_else(|| path.to_string()),
            tool,
            modes,
        })
    }
}

/// The lobes table as CSV: `spindle_rpm, critical_depth_mm, chatter_frequency_hz, kind,
/// steps_per_period`, one row per speed with a boundary; `steps_per_period` (the steps per
/// tooth period behind the point, see [`LobePoint::steps_per_period`]) is empty for the
/// zero-order solution, which has no time steps.
pub fn lobes_csv(points: &[LobePoint]) -> String {
    let mut s =
        String::from("spindle_rpm,critical_depth_mm,chatter_frequency_hz,kind,steps_per_period\n");
    for p in points {
        let _ = writeln!(
            s,
            "{},{:.6},{:.3},{},{}",
            p.spindle_rpm,
            p.critical_depth_mm,
            p.chatter_frequency_hz,
            kind_name(p.kind),
            p.steps_per_period.map_or(String::new(), |m| m.to_string())
        );
    }
    s
}

/// The text of a tool file (the format of the module doc) for `tool` and `modes`, named
/// `name`, with `comment` (any number of lines) as `#` lines at the top. Every value is written
/// in the shortest form that reads back to the same `f64` (each mode by its stiffness), so
/// [`ToolDynamics::from_toml_str`] gives back `tool` and `modes` bit for bit.
pub fn tool_file_toml(name: &str, comment: &str, tool: &Tool, modes: &TipModes) -> String {
    let mut s = String::new();
    for line in comment.lines() {
        let _ = writeln!(s, "#{}{line}", if line.is_empty() { "" } else { " " });
    }
    // TOML's own quoting of the name (escapes quotes, backslashes and control characters).
    let _ = writeln!(s, "name = {}", toml::Value::String(name.to_string()));
    let _ = writeln!(s, "\n[tool]");
    let _ = writeln!(s, "teeth = {}", tool.teeth);
    for (key, v) in [
        ("diameter_mm", tool.diameter_mm),
        ("helix_deg", tool.helix_deg),
        ("kt_n_per_m2", tool.kt_n_per_m2),
        ("kn_n_per_m2", tool.kn_n_per_m2),
        ("kte_n_per_m", tool.kte_n_per_m),
        ("kne_n_per_m", tool.kne_n_per_m),
        ("process_damping_n_per_m", tool.process_damping_n_per_m),
    ] {
        let _ = writeln!(s, "{key} = {}", toml_float(v));
    }
    for (direction, list) in [("x", &modes.x), ("y", &modes.y)] {
        for m in list {
            let _ = writeln!(s, "\n[[modes.{direction}]]");
            let _ = writeln!(s, "frequency_hz = {}", toml_float(m.frequency_hz));
            let _ = writeln!(s, "damping_ratio = {}", toml_float(m.damping_ratio));
            let _ = writeln!(s, "stiffness_n_per_m = {}", toml_float(m.stiffness_n_per_m));
        }
    }
    s
}

/// A finite `f64` as a TOML float that reads back bit for bit: Rust's shortest round-trip
/// form (`{:?}`: `16.0`, `1e-7`, `600000000.0`) is valid TOML.
fn toml_float(v: f64) -> String {
    format!("{v:?}")
}

/// The time series of one cut as CSV: `time_s, x_um, y_um, fx_n, fy_n` (tip displacement in
/// µm, cutting force on the tool in N), one row per integration step.
pub fn cut_csv(sim: &vmc_dynamics::CutSimulation) -> String {
    let mut s = String::with_capacity(48 * sim.displacement_m.len() + 32);
    s.push_str("time_s,x_um,y_um,fx_n,fy_n\n");
    for (i, (p, f)) in sim.displacement_m.iter().zip(&sim.force_n).enumerate() {
        let _ = writeln!(
            s,
            "{:.9},{:.6},{:.6},{:.6},{:.6}",
            sim.time_s(i),
            p[0] * 1e6,
            p[1] * 1e6,
            f[0],
            f[1]
        );
    }
    s
}

/// `hopf` or `flip`.
pub fn kind_name(kind: vmc_dynamics::BoundaryKind) -> &'static str {
    match kind {
        vmc_dynamics::BoundaryKind::Hopf => "hopf",
        vmc_dynamics::BoundaryKind::Flip => "flip",
    }
}

/// Spindle speeds from `first:last:count` (evenly spaced, both ends included) or a
/// comma-separated list, rpm.
///
/// # Errors
/// A malformed range or list, a count of 0, a speed that is not a positive number.
pub fn parse_speeds(text: &str) -> Result<Vec<f64>, String> {
    let speeds = parse_speed_list(text)?;
    if speeds.len() > MAX_SPEEDS {
        return Err(format!(
            "{} speeds, more than the limit of {MAX_SPEEDS} per run (each speed is a stability \
             computation); split the range over several runs, e.g. first:middle:count and \
             middle:last:count",
            speeds.len()
        ));
    }
    Ok(speeds)
}

/// Most spindle speeds one `--rpm` may give (a work limit: each is a stability computation).
pub const MAX_SPEEDS: usize = 20_000;

fn parse_speed_list(text: &str) -> Result<Vec<f64>, String> {
    let number = |s: &str| -> Result<f64, String> {
        let v: f64 = s
            .trim()
            .parse()
            .map_err(|_| format!("`{}` is not a number", s.trim()))?;
        if v > 0.0 && v.is_finite() {
            Ok(v)
        } else {
            Err(format!("a spindle speed must be > 0 rpm, got {v}"))
        }
    };
    let parts: Vec<&str> = text.split(':').collect();
    match parts.as_slice() {
        [first, last, count] => {
            let (a, b) = (number(first)?, number(last)?);
            let n: usize = count
                .trim()
                .parse()
                .map_err(|_| format!("`{}` is not a whole number of speeds", count.trim()))?;
            match n {
                0 => Err("the count of speeds must be at least 1".into()),
                1 if a == b => Ok(vec![a]),
                1 => Err(format!(
                    "a count of 1 cannot include both ends {a} and {b} rpm; give a count of at \
                     least 2, or the one speed alone (`{a}`)"
                )),
                n if n > MAX_SPEEDS => Err(format!(
                    "{n} speeds, more than the limit of {MAX_SPEEDS} per run (each speed is a \
                     stability computation); split the range over several runs, e.g. \
                     first:middle:count and middle:last:count"
                )),
                _ => Ok((0..n)
                    .map(|i| a + (b - a) * i as f64 / (n - 1) as f64)
                    .collect()),
            }
        }
        [list] => list.split(',').map(number).collect(),
        _ => Err(format!(
            "`{text}`: give first:last:count (e.g. 5000:25000:201) or a list (e.g. 5000,7500)"
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use vmc_dynamics::{lobes, Method, Milling};

    #[test]
    fn the_benchmark_tool_gives_the_closed_form_minimum_in_slotting() {
        let b = ToolDynamics::benchmark();
        // ZOA minimum in slotting: a_lim = 2kζ(1+ζ)/h̄, h̄ = N·K_n/4 (k from the modal mass).
        let m = b.modes.x[0];
        let h_bar = 2.0 * 2.0e8 / 4.0;
        let want_mm = 2.0 * m.stiffness_n_per_m * 0.011 * 1.011 / h_bar * 1e3;
        let speeds = parse_speeds("2000:30000:57").unwrap();
        let pts = lobes(Method::Zoa, &b.tool, &b.modes, 1.0, Milling::Down, &speeds).unwrap();
        let min = pts
            .iter()
            .map(|p| p.critical_depth_mm)
            .fold(f64::INFINITY, f64::min);
        // The sampled speeds touch the lobes' bottoms only approximately: within 5 %.
        assert!(min >= want_mm * (1.0 - 1e-9), "{min} vs {want_mm}");
        assert!(min < want_mm * 1.05, "{min} vs {want_mm}");
    }

    #[test]
    fn the_helical_benchmark_tool_loads_with_its_helix() {
        let t = ToolDynamics::from_toml_str(
            include_str!("../../../machines/benchmarks/helical-4flute-30deg.toml"),
            "machines/benchmarks/helical-4flute-30deg.toml",
        )
        .unwrap();
        assert_eq!((t.tool.teeth, t.tool.helix_deg), (4, 30.0));
        assert_eq!((t.modes.x.len(), t.modes.y.len()), (1, 1));
        let err = ToolDynamics::from_toml_str(
            &DEFAULT_TOOL_TOML.replacen("teeth = 2", "teeth = 2\nhelix_deg = 95.0", 1),
            "t.toml",
        )
        .unwrap_err();
        assert_eq!(
            err.to_string(),
            "t.toml: helix angle must be in [0, 90) deg, got 95"
        );
    }

    #[test]
    fn speeds_parse_as_a_range_or_a_list_and_bad_ones_are_named() {
        assert_eq!(
            parse_speeds("1000:2000:3").unwrap(),
            [1000.0, 1500.0, 2000.0]
        );
        assert_eq!(parse_speeds("5000, 7500").unwrap(), [5000.0, 7500.0]);
        // A count of 1 holds both ends only when they agree (the docs promise both ends).
        assert_eq!(parse_speeds("3000:3000:1").unwrap(), [3000.0]);
        assert!(parse_speeds("3000:4000:1")
            .unwrap_err()
            .contains("cannot include both ends"));
        // The work limit, before any speed is made, with the way beyond it.
        let e = parse_speeds("5000:6000:100000000").unwrap_err();
        assert!(
            e.contains("limit of 20000") && e.contains("several runs"),
            "{e}"
        );
        assert_eq!(parse_speeds("5000:6000:20000").unwrap().len(), MAX_SPEEDS);
        assert!(parse_speeds("1000:2000:0")
            .unwrap_err()
            .contains("at least 1"));
        assert!(parse_speeds("0,1000").unwrap_err().contains("> 0 rpm"));
        assert!(parse_speeds("1000:x:3")
            .unwrap_err()
            .contains("`x` is not a number"));
        assert!(parse_speeds("1:2:3:4")
            .unwrap_err()
            .contains("first:last:count"));
    }

    #[test]
    fn bad_tool_files_are_refused_with_the_file_and_the_field() {
        let with = |from: &str, to: &str| DEFAULT_TOOL_TOML.replacen(from, to, 1);
        let err = |text: String| {
            ToolDynamics::from_toml_str(&text, "t.toml")
                .unwrap_err()
                .to_string()
        };
        assert_eq!(
            err(with("teeth = 2", "teeth = 0")),
            "t.toml: the tool has no teeth"
        );
        assert!(
            err(with("damping_ratio = 0.011", "damping_ratio = -0.011")).starts_with("t.toml: ")
        );
        assert_eq!(
            err(with(
                "modal_mass_kg = 0.03993",
                "stiffness_n_per_m = 1e6\nmodal_mass_kg = 0.03993"
            )),
            "t.toml: modes.x[0]: give exactly one of stiffness_n_per_m and modal_mass_kg"
        );
        assert!(err(with("teeth = 2", "teeth = 2\nflutes = 3")).contains("flutes"));
    }

    #[test]
    fn the_csv_has_one_row_per_point_with_its_kind() {
        let b = ToolDynamics::benchmark();
        let pts = lobes(
            Method::Zoa,
            &b.tool,
            &b.modes,
            1.0,
            Milling::Down,
            &[5000.0],
        )
        .unwrap();
        let csv = lobes_csv(&pts);
        let lines: Vec<&str> = csv.lines().collect();
        assert_eq!(
            lines[0],
            "spindle_rpm,critical_depth_mm,chatter_frequency_hz,kind,steps_per_period"
        );
        assert_eq!(lines.len(), 1 + pts.len());
        // The zero-order solution has no time steps: the last field is empty.
        assert!(
            lines[1].starts_with("5000,") && lines[1].ends_with(",hopf,"),
            "{}",
            lines[1]
        );
        let sdm = lobes(
            Method::Sdm,
            &b.tool,
            &b.modes,
            1.0,
            Milling::Down,
            &[12_000.0],
        )
        .unwrap();
        let csv = lobes_csv(&sdm);
        let row = csv.lines().nth(1).unwrap();
        let steps = sdm[0].steps_per_period.unwrap();
        let kind = kind_name(sdm[0].kind);
        assert!(row.ends_with(&format!(",{kind},{steps}")), "{row}");
    }

    #[test]
    fn a_written_tool_file_reads_back_bit_for_bit() {
        let mut tool = ToolDynamics::benchmark().tool;
        tool.helix_deg = 30.0;
        tool.kte_n_per_m = 1.0 / 3.0;
        let modes = TipModes {
            x: vec![
                Mode::from_mass(922.0, 0.011, 0.03993),
                Mode {
                    frequency_hz: 2600.123456789,
                    damping_ratio: 0.0199,
                    stiffness_n_per_m: 6.02e7,
                },
            ],
            y: vec![Mode {
                frequency_hz: 700.5,
                damping_ratio: 1e-3,
                stiffness_n_per_m: 1.5e-7 * 1e14,
            }],
        };
        let name = "fit of \"a.csv\" \\ tab\there";
        let text = tool_file_toml(name, "first line\n\nthird line", &tool, &modes);
        assert!(
            text.starts_with("# first line\n#\n# third line\n"),
            "{text}"
        );
        let back = ToolDynamics::from_toml_str(&text, "fit.toml").unwrap();
        assert_eq!(back.name, name);
        assert_eq!(back.tool, tool);
        assert_eq!(back.modes, modes);
        // Bit for bit, not only equal as numbers.
        let bits = |m: &[Mode]| -> Vec<u64> {
            m.iter()
                .flat_map(|m| [m.frequency_hz, m.damping_ratio, m.stiffness_n_per_m])
                .map(f64::to_bits)
                .collect()
        };
        assert_eq!(bits(&back.modes.x), bits(&modes.x));
        assert_eq!(bits(&back.modes.y), bits(&modes.y));
        // A rigid direction writes no table and reads back empty.
        let rigid = TipModes {
            x: modes.x.clone(),
            y: Vec::new(),
        };
        let back =
            ToolDynamics::from_toml_str(&tool_file_toml("r", "", &tool, &rigid), "r").unwrap();
        assert!(back.modes.y.is_empty());
    }
}
