//! The twin: the simulated machine as it really is (truth side of DESIGN §3).
//!
//! It owns the thermal network, the error field of one random realisation (seed), the
//! approach-dependent random errors and the temperature sensors. The simulation loop advances it
//! with what the program does ([`Activity`]) and asks where the tool really is. Of all this, only
//! [`Twin::sensor_readings`] may reach a predictor or controller; the knowledge side lives in the
//! `vmc-predict` crate, which does not depend on this crate and so cannot name anything here.
//!
//! Volumetric error: with axes commanded to `q` (mm) the tool tip lands, relative to the
//! workpiece, at `q + E(q, T)`, where `E` is the full HTM product of the chain with the elementary
//! errors at `q` and node temperatures `T` (plus reversal and non-repeatability on the positioning
//! errors). The error seen against a commanded tool position `p` is `q + E(q, T) − p`.

use nalgebra::Vector3;
use thiserror::Error;

use crate::errors::{ApproachErrors, ErrorField, ErrorSpecError};
use crate::kinematics;
use crate::machine::MachineSpec;
use crate::predict::synthesis::{ElementaryErrors, MachineGeometry};
use crate::sensors::{SensorBank, SensorReadings};
use crate::thermal::{Activity, AmbientProfile, ThermalError, ThermalNetwork};

/// Why a twin could not be built or advanced.
#[derive(Debug, Error)]
pub enum TwinError {
    /// Error field problem.
    #[error(transparent)]
    Errors(#[from] ErrorSpecError),
    /// Thermal network problem.
    #[error(transparent)]
    Thermal(#[from] ThermalError),
    /// Sensor set problem.
    #[error("sensors: {0}")]
    Sensors(String),
}

/// Derives independent sub-seeds from one user seed (SplitMix64 finaliser).
pub fn sub_seed(seed: u64, stream: u64) -> u64 {
    let mut z = seed
        .wrapping_add(0x9E37_79B9_7F4A_7C15_u64.wrapping_mul(stream.wrapping_add(1)));
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// The simulated machine.
pub struct Twin {
    spec: MachineSpec,
    geometry: MachineGeometry,
    field: ErrorField,
    approach: ApproachErrors,
    thermal: ThermalNetwork,
    sensors: SensorBank,
}

impl Twin {
    /// Builds the machine of `spec`, random parts drawn from `seed`, at a uniform start
    /// temperature equal to the ambient's at t = 0 (a cold machine).
    pub fn new(spec: &MachineSpec, seed: u64) -> Result<Self, TwinError> {
        let thermal = ThermalNetwork::new(&spec.thermal, spec.thermal.ambient.temp_degc(0.0))?;
        let field = ErrorField::new(
            &spec.errors,
            spec.axes.travel_min_mm,
            spec.axes.travel_max_mm,
            &|n| thermal.node_index(n),
            sub_seed(seed, 0),
        )?;
        let sensors = SensorBank::new(&spec.sensors, thermal.node_names(), sub_seed(seed, 2))
            .map_err(|e| TwinError::Sensors(e.to_string()))?;
        let mut twin = Twin {
            geometry: spec.geometry(),
            field,
            approach: ApproachErrors::new(&spec.errors, sub_seed(seed, 1)),
            thermal,
            sensors,
            spec: spec.clone(),
        };
        twin.sensors
            .update(0.0, twin.thermal.temps_degc(), twin.thermal.ambient_degc())
            .map_err(|e| TwinError::Sensors(e.to_string()))?;
        Ok(twin)
    }

    /// The machine description it was built from.
    pub fn spec(&self) -> &MachineSpec {
        &self.spec
    }

    /// Nominal geometry (public knowledge).
    pub fn geometry(&self) -> &MachineGeometry {
        &self.geometry
    }

    /// Simulated time since the twin was built, s.
    pub fn time_s(&self) -> f64 {
        self.thermal.time_s()
    }

    /// Replaces the ambient temperature profile (times are absolute twin time).
    pub fn set_ambient(&mut self, ambient: AmbientProfile) -> Result<(), TwinError> {
        self.thermal.set_ambient(ambient)?;
        Ok(())
    }

    /// Advances heat flow and sensors by `dt_s` under `activity`.
    pub fn advance(&mut self, dt_s: f64, activity: &Activity) -> Result<(), TwinError> {
        self.thermal.advance(dt_s, activity)?;
        self.sensors
            .update(dt_s, self.thermal.temps_degc(), self.thermal.ambient_degc())
            .map_err(|e| TwinError::Sensors(e.to_string()))?;
        Ok(())
    }

    /// The latest sensor readings: the only run-time information a predictor gets.
    pub fn sensor_readings(&self) -> SensorReadings {
        self.sensors.read()
    }

    /// Records the direction in which each axis last moved (for the reversal error).
    pub fn note_motion(&mut self, vel: [f64; 3]) {
        self.approach.note_motion(vel);
    }

    /// Draws the random positioning parts (reversal + non-repeatability) of one approach, mm.
    pub fn draw_approach_mm(&mut self) -> [f64; 3] {
        self.approach.positioning_mm()
    }

    /// Truth: the 26 elementary errors at axis position `q_mm` and the current temperatures.
    pub fn elementary_errors(&self, q_mm: [f64; 3]) -> ElementaryErrors {
        self.field.elementary(q_mm, self.thermal.temps_degc())
    }

    /// Truth: tool tip relative to the workpiece minus `p_mm`, with axes at `q_mm` and the given
    /// random positioning parts (mm). Full HTM product.
    pub fn tool_error_mm(&self, p_mm: [f64; 3], q_mm: [f64; 3], approach_mm: [f64; 3]) -> Vector3<f64> {
        let mut e = self.elementary_errors(q_mm);
        for a in 0..3 {
            e.axes[a].lin_mm[a] += approach_mm[a];
        }
        let err = kinematics::full_error_mm(&self.geometry, q_mm, &e);
        Vector3::from(q_mm) + err - Vector3::from(p_mm)
    }

    /// Truth, for reports: the same error as [`Twin::tool_error_mm`] but with every thermal node
    /// at the error field's reference temperature, i.e. the machine's cold geometry. The
    /// difference between the two is the thermal part of the error.
    pub fn tool_error_at_ref_temp_mm(&self, p_mm: [f64; 3], q_mm: [f64; 3], approach_mm: [f64; 3]) -> Vector3<f64> {
        let cold = vec![self.field.ref_temp_degc(); self.thermal.temps_degc().len()];
        let mut e = self.field.elementary(q_mm, &cold);
        for a in 0..3 {
            e.axes[a].lin_mm[a] += approach_mm[a];
        }
        let err = kinematics::full_error_mm(&self.geometry, q_mm, &e);
        Vector3::from(q_mm) + err - Vector3::from(p_mm)
    }

    /// Truth, for tests and instruments: node temperatures, °C.
    pub fn node_temps_degc(&self) -> &[f64] {
        self.thermal.temps_degc()
    }

    /// Truth side, for tests and what-if studies: overwrites every thermal node temperature, °C
    /// (one value per node, in [`Twin::node_names`] order). Time does not move; the sensors keep
    /// their readings and follow the new temperatures with their own time constants at the next
    /// [`Twin::advance`].
    pub fn set_node_temps_degc(&mut self, temps_degc: &[f64]) -> Result<(), TwinError> {
        self.thermal.set_temps_degc(temps_degc)?;
        Ok(())
    }

    /// Truth, for tests and instruments: node names.
    pub fn node_names(&self) -> &[String] {
        self.thermal.node_names()
    }

    /// Ambient temperature now, °C.
    pub fn ambient_degc(&self) -> f64 {
        self.thermal.ambient_degc()
    }
}
