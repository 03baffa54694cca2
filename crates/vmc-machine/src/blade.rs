//! The app side of the active-control study: the plant file (a blade, its piezo actuator, the
//! cutter, the cut and the controller weights; TOML) and the controller file (JSON) that
//! `vmc-twin control design` writes and `lobes`/`cut --controller` read. The numerics are in
//! [`vmc_dynamics::control`]; this module only reads, checks and writes.
//!
//! A plant file (units in names, unknown fields refused; see docs/file-formats.md):
//!
//! ```toml
//! name = "piezo blade"
//! [blade]                      # vmc_dynamics::control::blade::Blade
//! youngs_modulus_pa = 210e9
//! density_kg_per_m3 = 7850.0
//! length_mm = 160.0            # clamp to free end
//! width_mm = 80.0              # along the cutter axis
//! thickness_mm = 5.0           # bending direction
//! modes = 4
//! damping_ratio = 0.01
//! sensor_position_mm = 160.0
//! [blade.actuator]
//! position_mm = 36.0
//! stiffness_n_per_um = 185.0
//! stroke_um = 30.0
//! max_voltage_v = 150.0
//! bandwidth_hz = 2000.0
//! [tool]                       # as in a tool file
//! teeth = 2
//! diameter_mm = 16.0
//! kt_n_per_m2 = 1.0e9
//! kn_n_per_m2 = 3.0e8
//! [cut]
//! spindle_rpm = 2800.0
//! feed_per_tooth_mm = 0.08
//! radial_depth_mm = 1.0
//! milling = "down"
//! speed_band_rpm = [1500.0, 4500.0]
//! [controller]
//! sample_rate_hz = 50000.0
//! [lqg]  …   [hinf]  …   [robust_hinf]  …   [strategy2]  …
//! ```
//!
//! A controller file is refused when its stored plant does not give the closed-loop poles
//! stored with it (the plant or the matrices were edited), or when its sampling cannot see
//! the modes it acts on ([`vmc_dynamics::control::robust::check_sampling`]).

use std::path::Path;

use nalgebra::DMatrix;
use serde::{Deserialize, Serialize};
use thiserror::Error;

use crate::milling::ToolSection;
use crate::read;
use vmc_dynamics::control::blade::Blade;
use vmc_dynamics::control::design::{HinfWeights, LqgWeights};
use vmc_dynamics::control::robust::RobustWeights;
use vmc_dynamics::control::StateSpace;
use vmc_dynamics::{Milling, Tool};

/// The plant file as read.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct PlantFile {
    name: Option<String>,
    blade: Blade,
    tool: ToolSection,
    cut: CutSection,
    controller: SamplingSection,
    lqg: LqgWeights,
    hinf: HinfWeights,
    #[serde(default)]
    robust_hinf: Option<RobustWeights>,
    #[serde(default)]
    strategy2: Option<Strategy2Section>,
}

/// The robust H∞ weights when a plant file gives none: relative input uncertainty 1 below
/// 800 Hz rising to 20 above (the blade's second and higher modes), roll-off at 2 kHz (see
/// docs/decisions/2026-11-28-robust-chatter-control.md).
pub const DEFAULT_ROBUST_WEIGHTS: RobustWeights = RobustWeights {
    uncertainty_low: 1.0,
    uncertainty_high: 20.0,
    uncertainty_corner_hz: 800.0,
    rolloff_hz: 2000.0,
};

fn default_robust() -> RobustWeights {
    DEFAULT_ROBUST_WEIGHTS
}

/// Fewest samples per period of the highest mode a controller acts on: the Nyquist rate
/// with a margin of 2.5 (a mode sampled at its Nyquist rate is seen but not controlled: the
/// one-sample delay alone is half a period).
pub const SAMPLES_PER_ACTED_PERIOD: f64 = 5.0;

/// A mode counts as acted on when the controller changes its peak by more than this, dB.
pub const ACTING_DB: f64 = 1.0;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct CutSection {
    spindle_rpm: f64,
    feed_per_tooth_mm: f64,
    radial_depth_mm: f64,
    milling: MillingName,
    speed_band_rpm: [f64; 2],
}

#[derive(Deserialize, Serialize, Clone, Copy, Debug, PartialEq)]
#[serde(rename_all = "lowercase")]
enum MillingName {
    Up,
    Down,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SamplingSection {
    sample_rate_hz: f64,
}

/// Strategy 2's design cut.
#[derive(Deserialize, Serialize, Clone, Copy, Debug, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Strategy2Section {
    /// Axial depth the design couples the cut at, mm.
    pub design_depth_mm: f64,
    /// Order of the Padé approximation of the delay.
    pub pade_order: usize,
    /// Design speed, rpm (default: the cut's speed).
    #[serde(default)]
    pub design_rpm: Option<f64>,
}

/// A validated plant file: the blade, the cutter, the cut and the design settings.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Plant {
    /// The file's `name` (or its path).
    pub name: String,
    /// The blade and its actuator.
    pub blade: Blade,
    /// The cutter.
    pub tool: Tool,
    /// Nominal spindle speed, rpm.
    pub spindle_rpm: f64,
    /// Feed per tooth, mm.
    pub feed_per_tooth_mm: f64,
    /// Radial immersion a_e/D.
    pub immersion: f64,
    /// Up or down milling.
    pub milling: Milling,
    /// Speed band of the lobes, rpm (low, high).
    pub speed_band_rpm: [f64; 2],
    /// Controller sample rate, Hz.
    pub sample_rate_hz: f64,
    /// LQG weights.
    pub lqg: LqgWeights,
    /// H∞ weights.
    pub hinf: HinfWeights,
    /// The robust H∞ design's uncertainty and roll-off weights (with the H∞ weights).
    #[serde(default = "default_robust")]
    pub robust_hinf: RobustWeights,
    /// Strategy 2's design cut, if given.
    pub strategy2: Option<Strategy2Section>,
}

impl Plant {
    /// Reads and checks a plant file.
    ///
    /// # Errors
    /// Unreadable, not TOML, not the schema, or values the dynamics refuses.
    pub fn load(path: &Path) -> Result<Self, BladeFileError> {
        let text = read::read_named(path, "plant file")?;
        Self::from_toml_str(&text, &path.display().to_string())
    }

    /// Parses and checks a plant file's text; `path` names it in errors.
    ///
    /// # Errors
    /// See [`Plant::load`].
    pub fn from_toml_str(text: &str, path: &str) -> Result<Self, BladeFileError> {
        let invalid = |message: String| BladeFileError::Invalid {
            file: path.to_string(),
            message,
        };
        let f: PlantFile =
            toml::from_str(text).map_err(|e| invalid(read::one_line_toml_error(&e)))?;
        let tool = f.tool.to_tool();
        tool.validate().map_err(|e| invalid(format!("tool: {e}")))?;
        f.blade
            .validate()
            .map_err(|e| invalid(format!("blade: {e}")))?;
        let c = &f.cut;
        let immersion = c.radial_depth_mm / tool.diameter_mm;
        vmc_dynamics::params::validate_immersion(immersion)
            .map_err(|e| invalid(format!("cut.radial_depth_mm / tool.diameter_mm: {e}")))?;
        vmc_dynamics::params::validate_speed(c.spindle_rpm)
            .map_err(|e| invalid(format!("cut.spindle_rpm: {e}")))?;
        let [lo, hi] = c.speed_band_rpm;
        if !(lo > 0.0 && hi > lo && hi.is_finite()) {
            return Err(invalid(format!(
                "cut.speed_band_rpm must be [low, high] with 0 < low < high, got [{lo}, {hi}]"
            )));
        }
        if !(c.feed_per_tooth_mm > 0.0 && c.feed_per_tooth_mm.is_finite()) {
            return Err(invalid(format!(
                "cut.feed_per_tooth_mm must be > 0, got {}",
                c.feed_per_tooth_mm
            )));
        }
        let rate = f.controller.sample_rate_hz;
        if !(rate > 0.0 && rate.is_finite()) {
            return Err(invalid(format!(
                "controller.sample_rate_hz must be > 0, got {rate}"
            )));
        }
        check_weights(&f.lqg, &f.hinf, f.robust_hinf.as_ref()).map_err(invalid)?;
        Ok(Self {
            name: f.name.unwrap_or_else(|| path.to_string()),
            blade: f.blade,
            tool,
            spindle_rpm: c.spindle_rpm,
            feed_per_tooth_mm: c.feed_per_tooth_mm,
            immersion,
            milling: match c.milling {
                MillingName::Up => Milling::Up,
                MillingName::Down => Milling::Down,
            },
            speed_band_rpm: c.speed_band_rpm,
            sample_rate_hz: rate,
            lqg: f.lqg,
            hinf: f.hinf,
            robust_hinf: f.robust_hinf.unwrap_or(DEFAULT_ROBUST_WEIGHTS),
            strategy2: f.strategy2,
        })
    }
}

/// Checks the weights of the three designs (each must be positive; the names are the file's).
fn check_weights(
    lqg: &LqgWeights,
    hinf: &HinfWeights,
    robust: Option<&RobustWeights>,
) -> Result<(), String> {
    let fields = [
        ("lqg.tip_weight_per_um2", lqg.tip_weight_per_um2),
        ("lqg.effort_weight_per_v2", lqg.effort_weight_per_v2),
        ("lqg.force_intensity_n2", lqg.force_intensity_n2),
        ("lqg.noise_intensity_um2", lqg.noise_intensity_um2),
        ("hinf.tip_weight_per_um", hinf.tip_weight_per_um),
        ("hinf.effort_weight_per_v", hinf.effort_weight_per_v),
        ("hinf.force_scale_n", hinf.force_scale_n),
        ("hinf.noise_scale_um", hinf.noise_scale_um),
    ];
    let corners = [
        ("lqg.lowpass_hz", lqg.lowpass_hz),
        ("hinf.lowpass_hz", hinf.lowpass_hz),
    ];
    for (name, v) in fields
        .into_iter()
        .chain(corners.into_iter().filter_map(|(n, v)| v.map(|v| (n, v))))
    {
        if !(v > 0.0 && v.is_finite()) {
            return Err(format!("{name} must be > 0, got {v}"));
        }
    }
    if let Some(r) = robust {
        r.validate().map_err(|e| format!("robust_hinf: {e}"))?;
    }
    Ok(())
}

/// A matrix as rows (JSON).
pub type Rows = Vec<Vec<f64>>;

fn rows(m: &DMatrix<f64>) -> Rows {
    (0..m.nrows())
        .map(|i| (0..m.ncols()).map(|j| m[(i, j)]).collect())
        .collect()
}

fn matrix(
    r: &Rows,
    what: &'static str,
    nrows: usize,
    ncols: usize,
) -> Result<DMatrix<f64>, ControllerError> {
    if r.len() != nrows || r.iter().any(|row| row.len() != ncols) {
        return Err(ControllerError::Shape { what, nrows, ncols });
    }
    if r.iter().flatten().any(|v| !v.is_finite()) {
        return Err(ControllerError::NotFinite { what });
    }
    Ok(DMatrix::from_fn(nrows, ncols, |i, j| r[i][j]))
}

/// The controller's matrices: ẋ_K = A x_K + B y, u = C x_K + D y (y in m, u in V).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ControllerMatrices {
    /// A (n × n).
    pub a: Rows,
    /// B (n × 1).
    pub b: Rows,
    /// C (1 × n).
    pub c: Rows,
    /// D (1 × 1).
    pub d: Rows,
}

/// One mode's attenuation in the controller file.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ModeFigure {
    /// Frequency with the stack held, Hz.
    pub frequency_hz: f64,
    /// Open-loop peak |z/F|, m/N.
    pub open_peak_m_per_n: f64,
    /// Closed-loop peak |z/F|, m/N.
    pub closed_peak_m_per_n: f64,
    /// Attenuation, dB.
    pub attenuation_db: f64,
}

/// The figures of a design.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Figures {
    /// Closed-loop poles [re, im] in rad/s (continuous model with the sampling delay).
    pub poles_rad_per_s: Vec<[f64; 2]>,
    /// Attenuation of each mode.
    pub modes: Vec<ModeFigure>,
    /// Peak |u/F|, V/N.
    pub effort_peak_v_per_n: f64,
    /// Frequency of that peak, Hz.
    pub effort_peak_hz: f64,
    /// Spectral radius of the exact sampled loop (stable below 1).
    pub sampled_loop_spectral_radius: f64,
}

/// The controller file (`ctrl.json`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ControllerFile {
    /// Format tag.
    pub format: String,
    /// `lqg`, `hinf` or `robust-hinf`.
    pub kind: String,
    /// 1 (structure alone) or 2 (structure coupled to the cut).
    pub strategy: u8,
    /// H∞: the γ the controller was built for.
    pub gamma: Option<f64>,
    /// The plant the controller was designed for.
    pub plant: Plant,
    /// The controller.
    pub controller: ControllerMatrices,
    /// Its figures.
    pub figures: Figures,
}

/// The format tag of a controller file.
pub const CONTROLLER_FORMAT: &str = "vmc-twin controller 1";

impl ControllerFile {
    /// The controller's matrices from a state-space model.
    pub fn matrices(k: &StateSpace) -> ControllerMatrices {
        ControllerMatrices {
            a: rows(&k.a),
            b: rows(&k.b),
            c: rows(&k.c),
            d: rows(&k.d),
        }
    }

    /// The controller as a state-space model (checked dimensions and values).
    ///
    /// # Errors
    /// Matrices of the wrong shape or with non-finite values.
    pub fn state_space(&self) -> Result<StateSpace, ControllerError> {
        let m = &self.controller;
        let n = m.a.len();
        Ok(StateSpace {
            a: matrix(&m.a, "a", n, n)?,
            b: matrix(&m.b, "b", n, 1)?,
            c: matrix(&m.c, "c", 1, n)?,
            d: matrix(&m.d, "d", 1, 1)?,
        })
    }

    /// Reads and checks a controller file.
    ///
    /// # Errors
    /// Unreadable, not JSON, not the schema or its format tag, bad matrices or plant.
    pub fn load(path: &Path) -> Result<Self, BladeFileError> {
        let text = read::read_named(path, "controller file")?;
        let invalid = |message: String| BladeFileError::Invalid {
            file: path.display().to_string(),
            message,
        };
        let f: Self = serde_json::from_str(&text)
            .map_err(|e| invalid(format!("not a controller file: {e}")))?;
        if f.format != CONTROLLER_FORMAT {
            return Err(invalid(format!(
                "format is `{}`, expected `{CONTROLLER_FORMAT}`",
                f.format
            )));
        }
        f.state_space().map_err(|e| invalid(e.to_string()))?;
        f.plant
            .blade
            .validate()
            .map_err(|e| invalid(format!("plant.blade: {e}")))?;
        f.plant
            .tool
            .validate()
            .map_err(|e| invalid(format!("plant.tool: {e}")))?;
        f.check_consistent().map_err(|e| invalid(e.to_string()))?;
        Ok(f)
    }

    /// Checks that the stored plant and matrices give the stored closed-loop poles (an edited
    /// plant or matrix is refused: figures and guarantees would belong to another loop) and
    /// that the sampling can act on the modes the figures claim.
    ///
    /// # Errors
    /// A pole that moved, a sampling that cannot see an acted-on mode.
    pub fn check_consistent(&self) -> Result<(), ControllerError> {
        use vmc_dynamics::control::closed_loop::{close, sampled_model};
        let k = self.state_space()?;
        let plant = self.plant.blade.plant()?;
        let closed = close(&plant, &sampled_model(&k, self.plant.sample_rate_hz)?)?;
        let mut poles: Vec<[f64; 2]> = closed.poles().iter().map(|l| [l.re, l.im]).collect();
        poles.sort_by(|a, b| (a[0].hypot(a[1])).total_cmp(&b[0].hypot(b[1])));
        let stored = &self.figures.poles_rad_per_s;
        let scale = poles.iter().fold(1.0f64, |m, p| m.max(p[0].hypot(p[1])));
        let matches = stored.len() == poles.len()
            && stored
                .iter()
                .zip(&poles)
                .all(|(s, p)| (s[0] - p[0]).hypot(s[1].abs() - p[1].abs()) <= 1e-6 * scale);
        if !matches {
            return Err(ControllerError::PolesMoved);
        }
        let modes: Vec<(f64, f64)> = self
            .figures
            .modes
            .iter()
            .map(|m| (m.frequency_hz, m.attenuation_db))
            .collect();
        vmc_dynamics::control::robust::check_sampling(
            &modes,
            self.plant.sample_rate_hz,
            ACTING_DB,
            SAMPLES_PER_ACTED_PERIOD / 2.0,
        )?;
        Ok(())
    }
}

/// A plant or controller file that cannot be used.
#[derive(Debug, Error)]
pub enum BladeFileError {
    /// The file could not be read.
    #[error(transparent)]
    Read(#[from] read::ReadError),
    /// Not the format, or a value the file may not hold (the message names the field).
    #[error("{file}: {message}")]
    Invalid {
        /// The file.
        file: String,
        /// What is wrong, naming the field.
        message: String,
    },
}

/// A controller that cannot be used as stored.
#[derive(Debug, Error)]
pub enum ControllerError {
    /// A matrix of the wrong shape.
    #[error("controller.{what} must be {nrows} x {ncols}")]
    Shape {
        /// The matrix (`a`, `b`, `c`, `d`).
        what: &'static str,
        /// Rows it must have.
        nrows: usize,
        /// Columns it must have.
        ncols: usize,
    },
    /// A matrix with a value that is not a finite number.
    #[error("controller.{what} has a value that is not a finite number")]
    NotFinite {
        /// The matrix (`a`, `b`, `c`, `d`).
        what: &'static str,
    },
    /// The stored plant or its closed loop cannot be built.
    #[error(transparent)]
    Dynamics(#[from] vmc_dynamics::DynamicsError),
    /// The closed loop or the sampling check failed.
    #[error(transparent)]
    Control(#[from] vmc_dynamics::control::ControlError),
    /// The stored poles are not those of the stored plant and matrices.
    #[error("the stored plant and controller matrices do not give the closed-loop poles stored with them (the plant or the matrices were edited): design the controller again with `vmc-twin control design`, and judge it on another blade with --plant FILE")]
    PolesMoved,
}

#[cfg(test)]
mod tests {
    use super::*;

    const BLADE: &str = include_str!("../../../machines/benchmarks/blade.toml");

    #[test]
    fn the_shipped_blade_loads_with_the_studys_cut() {
        let p = Plant::from_toml_str(BLADE, "blade.toml").unwrap();
        assert_eq!(p.tool.teeth, 2);
        assert!((p.immersion - 1.0 / 16.0).abs() < 1e-12);
        assert!((p.tool.kt_n_per_m2 - 1e9).abs() < 1.0);
        assert!((p.blade.propped_tip_stiffness_n_per_mm() / 215.7 - 1.0).abs() < 0.01);
    }

    #[test]
    fn bad_plant_files_name_the_field() {
        let bad = BLADE.replace("thickness_mm = 5.0", "thickness_mm = -5.0");
        let e = Plant::from_toml_str(&bad, "b.toml")
            .unwrap_err()
            .to_string();
        assert!(e.contains("thickness_mm"), "{e}");
        let bad = BLADE.replace("radial_depth_mm = 1.0", "radial_depth_mm = 20.0");
        let e = Plant::from_toml_str(&bad, "b.toml")
            .unwrap_err()
            .to_string();
        assert!(e.contains("radial_depth_mm"), "{e}");
        let bad = BLADE.replace("[cut]", "[cut]\nunknown = 1");
        assert!(Plant::from_toml_str(&bad, "b.toml").is_err());
    }
}
