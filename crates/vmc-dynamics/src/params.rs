//! Parameters of the milling-dynamics model and their validation.
//!
//! Units are SI except where the name says otherwise (`_mm`, `_rpm`, `_deg`).
//! Every parameter struct is plain data; `validate` returns the first
//! [`DynamicsError`] found.

use serde::{Deserialize, Serialize};
use thiserror::Error;

/// Errors of parameter validation and of the numerical methods.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum DynamicsError {
    /// The tool has no teeth.
    #[error("the tool has no teeth")]
    NoTeeth,
    /// A parameter is NaN or infinite.
    #[error("{name} is not finite")]
    NonFinite {
        /// Name of the parameter.
        name: &'static str,
    },
    /// A parameter that must be strictly positive is not.
    #[error("{name} must be > 0, got {value}")]
    NonPositive {
        /// Name of the parameter.
        name: &'static str,
        /// The value given.
        value: f64,
    },
    /// A parameter that must be non-negative is negative.
    #[error("{name} must be >= 0, got {value}")]
    Negative {
        /// Name of the parameter.
        name: &'static str,
        /// The value given.
        value: f64,
    },
    /// Radial immersion a_e/D is outside [`MIN_IMMERSION`], 1].
    #[error(
        "immersion a_e/D must be in [{MIN_IMMERSION}, 1] (a radial depth of at least 1 % of the \
         tool diameter), got {}", readable(*.0)
    )]
    ImmersionOutOfRange(f64),
    /// The spindle speed is zero (or negative).
    #[error("spindle speed must be > 0 rpm, got {0}")]
    ZeroSpeed(f64),
    /// The spindle speed is positive but below [`MIN_SPINDLE_RPM`].
    #[error("spindle speed {} rpm is below {MIN_SPINDLE_RPM} rpm: a tooth period of minutes or more is not a milling cut (milling runs at hundreds to tens of thousands of rpm)", readable(*.0))]
    SpeedTooLow(f64),
    /// The spindle speed is above [`MAX_SPINDLE_RPM`].
    #[error("spindle speed {} rpm is above {MAX_SPINDLE_RPM} rpm, faster than any machine-tool spindle", readable(*.0))]
    SpeedTooHigh(f64),
    /// Neither direction has a mode.
    #[error("at least one mode in x or y is required")]
    NoModes,
    /// The helix angle is outside [0, 90) degrees.
    #[error("helix angle must be in [0, 90) deg, got {0}")]
    HelixOutOfRange(f64),
    /// The steady (tooth-periodic) forced vibration of a cut does not exist: an undamped mode
    /// is excited at one of its natural frequencies.
    #[error("the cut has no steady vibration (an undamped mode resonates with the tooth passing)")]
    NoSteadyState,
    /// A count is too large.
    #[error("{name} must be <= {max}, got {value}")]
    TooManySteps {
        /// Name of the count.
        name: &'static str,
        /// Largest accepted value.
        max: usize,
        /// The value given.
        value: usize,
    },
    /// A discretisation count is too small.
    #[error("{name} must be >= {min}, got {value}")]
    TooFewSteps {
        /// Name of the count.
        name: &'static str,
        /// Smallest accepted value.
        min: usize,
        /// The value given.
        value: usize,
    },
}

pub(crate) fn finite(name: &'static str, v: f64) -> Result<(), DynamicsError> {
    if v.is_finite() {
        Ok(())
    } else {
        Err(DynamicsError::NonFinite { name })
    }
}

pub(crate) fn positive(name: &'static str, v: f64) -> Result<(), DynamicsError> {
    finite(name, v)?;
    if v > 0.0 {
        Ok(())
    } else {
        Err(DynamicsError::NonPositive { name, value: v })
    }
}

pub(crate) fn non_negative(name: &'static str, v: f64) -> Result<(), DynamicsError> {
    finite(name, v)?;
    if v >= 0.0 {
        Ok(())
    } else {
        Err(DynamicsError::Negative { name, value: v })
    }
}

/// An end mill with straight or helical teeth and linear cutting-force coefficients.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Tool {
    /// Number of teeth N (uniform pitch).
    pub teeth: u32,
    /// Diameter D in mm.
    pub diameter_mm: f64,
    /// Helix angle β in degrees, in [0, 90) (default 0: straight teeth). A point of a tooth at
    /// height z above the tip lags the tip by the angle 2 z tanβ / D.
    pub helix_deg: f64,
    /// Tangential specific cutting force K_t in N/m².
    pub kt_n_per_m2: f64,
    /// Normal (radial) specific cutting force K_n in N/m².
    pub kn_n_per_m2: f64,
    /// Tangential edge coefficient in N/m (default 0; static force only).
    pub kte_n_per_m: f64,
    /// Normal edge coefficient in N/m (default 0; static force only).
    pub kne_n_per_m: f64,
    /// Process-damping coefficient C in N/m (default 0): force -C·a_p/v_c·ṅ along the normal.
    pub process_damping_n_per_m: f64,
}

impl Tool {
    /// A straight-tooth tool without edge forces or process damping.
    pub fn new(teeth: u32, diameter_mm: f64, kt_n_per_m2: f64, kn_n_per_m2: f64) -> Self {
        Self {
            teeth,
            diameter_mm,
            helix_deg: 0.0,
            kt_n_per_m2,
            kn_n_per_m2,
            kte_n_per_m: 0.0,
            kne_n_per_m: 0.0,
            process_damping_n_per_m: 0.0,
        }
    }

    /// Checks counts, signs, finiteness and the helix range [0, 90) deg.
    pub fn validate(&self) -> Result<(), DynamicsError> {
        if self.teeth == 0 {
            return Err(DynamicsError::NoTeeth);
        }
        positive("diameter_mm", self.diameter_mm)?;
        finite("helix_deg", self.helix_deg)?;
        if !(0.0..90.0).contains(&self.helix_deg) {
            return Err(DynamicsError::HelixOutOfRange(self.helix_deg));
        }
        non_negative("kt_n_per_m2", self.kt_n_per_m2)?;
        non_negative("kn_n_per_m2", self.kn_n_per_m2)?;
        non_negative("kte_n_per_m", self.kte_n_per_m)?;
        non_negative("kne_n_per_m", self.kne_n_per_m)?;
        non_negative("process_damping_n_per_m", self.process_damping_n_per_m)
    }

    /// Lag angle per metre of height k_β = 2 tanβ / D in rad/m (0 for straight teeth).
    pub fn lag_rad_per_m(&self) -> f64 {
        if self.helix_deg == 0.0 {
            return 0.0;
        }
        2.0 * self.helix_deg.to_radians().tan() / (self.diameter_mm * 1e-3)
    }

    /// Tooth-passing period τ = 60/(N·n) in s, which is also the regenerative delay.
    pub fn tooth_period_s(&self, spindle_rpm: f64) -> f64 {
        60.0 / (f64::from(self.teeth) * spindle_rpm)
    }
}

/// One vibration mode at the tool tip (mode shape normalised to 1 at the tip).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Mode {
    /// Natural frequency in Hz.
    pub frequency_hz: f64,
    /// Damping ratio ζ (dimensionless, >= 0).
    pub damping_ratio: f64,
    /// Modal stiffness at the tip in N/m.
    pub stiffness_n_per_m: f64,
}

impl Mode {
    /// A mode given by its modal mass instead of its stiffness: k = m·ω².
    pub fn from_mass(frequency_hz: f64, damping_ratio: f64, modal_mass_kg: f64) -> Self {
        let w = 2.0 * std::f64::consts::PI * frequency_hz;
        Self {
            frequency_hz,
            damping_ratio,
            stiffness_n_per_m: modal_mass_kg * w * w,
        }
    }

    /// Angular natural frequency in rad/s.
    pub fn omega_rad_per_s(&self) -> f64 {
        2.0 * std::f64::consts::PI * self.frequency_hz
    }

    /// Modal mass m = k/ω² in kg.
    pub fn modal_mass_kg(&self) -> f64 {
        let w = self.omega_rad_per_s();
        self.stiffness_n_per_m / (w * w)
    }

    /// Checks positivity of frequency and stiffness and non-negative damping.
    pub fn validate(&self) -> Result<(), DynamicsError> {
        positive("frequency_hz", self.frequency_hz)?;
        non_negative("damping_ratio", self.damping_ratio)?;
        positive("stiffness_n_per_m", self.stiffness_n_per_m)
    }
}

/// Modes of the tool tip in the two feed-plane directions; an empty list means rigid.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct TipModes {
    /// Modes in x (feed direction).
    pub x: Vec<Mode>,
    /// Modes in y (normal to feed).
    pub y: Vec<Mode>,
}

impl TipModes {
    /// Flexible in x only (y rigid), the classical 1-DOF benchmark layout.
    pub fn x_only(modes: Vec<Mode>) -> Self {
        Self {
            x: modes,
            y: Vec::new(),
        }
    }

    /// The same single mode in x and in y.
    pub fn symmetric(mode: Mode) -> Self {
        Self {
            x: vec![mode],
            y: vec![mode],
        }
    }

    /// Checks that there is a mode and that every mode is valid.
    pub fn validate(&self) -> Result<(), DynamicsError> {
        if self.x.is_empty() && self.y.is_empty() {
            return Err(DynamicsError::NoModes);
        }
        self.x
            .iter()
            .chain(self.y.iter())
            .try_for_each(Mode::validate)
    }

    /// Total number of modes.
    pub fn len(&self) -> usize {
        self.x.len() + self.y.len()
    }

    /// True when there is no mode.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// Milling direction.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum Milling {
    /// Up (conventional) milling: a tooth enters at zero chip thickness.
    Up,
    /// Down (climb) milling: a tooth exits at zero chip thickness.
    Down,
}

/// One cutting condition.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Cut {
    /// Spindle speed in rpm.
    pub spindle_rpm: f64,
    /// Radial immersion a_e/D in [0.01, 1].
    pub immersion: f64,
    /// Up or down milling.
    pub milling: Milling,
    /// Feed per tooth in mm.
    pub feed_per_tooth_mm: f64,
    /// Axial depth of cut a_p in mm.
    pub axial_depth_mm: f64,
}

impl Cut {
    /// Checks speed, immersion, feed and depth.
    pub fn validate(&self) -> Result<(), DynamicsError> {
        validate_speed(self.spindle_rpm)?;
        validate_immersion(self.immersion)?;
        non_negative("feed_per_tooth_mm", self.feed_per_tooth_mm)?;
        non_negative("axial_depth_mm", self.axial_depth_mm)
    }
}

/// Checks that a spindle speed is finite and in [[`MIN_SPINDLE_RPM`], [`MAX_SPINDLE_RPM`]].
pub fn validate_speed(spindle_rpm: f64) -> Result<(), DynamicsError> {
    finite("spindle_rpm", spindle_rpm)?;
    if spindle_rpm > MAX_SPINDLE_RPM {
        Err(DynamicsError::SpeedTooHigh(spindle_rpm))
    } else if spindle_rpm >= MIN_SPINDLE_RPM {
        Ok(())
    } else if spindle_rpm > 0.0 {
        Err(DynamicsError::SpeedTooLow(spindle_rpm))
    } else {
        Err(DynamicsError::ZeroSpeed(spindle_rpm))
    }
}

/// Slowest spindle speed the dynamics accepts, rpm (below, a tooth period lasts minutes and
/// the models' notion of a steady cut, its spectra and step counts lose their meaning).
pub const MIN_SPINDLE_RPM: f64 = 1.0;

/// Fastest spindle speed the dynamics accepts, rpm (the machine files' bound for a speed; the
/// fastest machining spindles turn at about 10⁵ rpm).
pub const MAX_SPINDLE_RPM: f64 = 2e5;

/// A number as a person reads it in a message: plain between 10⁻⁴ and 10⁶, else in exponent
/// form (never three hundred digits).
pub fn readable(v: f64) -> String {
    if v == 0.0 || !v.is_finite() || (1e-4..1e6).contains(&v.abs()) {
        format!("{v}")
    } else {
        format!("{v:e}")
    }
}

/// Smallest radial immersion a_e/D accepted: 1 % of the diameter (0.1 mm on a 10 mm cutter, a
/// light finishing pass). Below, the tooth is in the cut for under 12° of its turn, the
/// discretised models need thousands of steps per period, and the limiting depths they give run
/// to metres or kilometres: numbers without a physical cut behind them.
pub const MIN_IMMERSION: f64 = 0.01;

/// Checks that a_e/D is finite and in [[`MIN_IMMERSION`], 1].
pub fn validate_immersion(immersion: f64) -> Result<(), DynamicsError> {
    finite("immersion", immersion)?;
    if (MIN_IMMERSION..=1.0).contains(&immersion) {
        Ok(())
    } else {
        Err(DynamicsError::ImmersionOutOfRange(immersion))
    }
}
