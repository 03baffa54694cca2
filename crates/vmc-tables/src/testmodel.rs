//! An analytic error model for the unit tests: every value a table should hold, and every
//! residual a check should report, follows from its formula by hand (mm, °C):
//!
//! ```text
//! Ex = 2e-7 (x − 280)² + 1e-5 y − 1e-5 z + 1e-3 (T − 20) + 1e-8 (x − 280)(y − 200)
//! Ey = 3e-3 sin(x / 150) + 5e-6 (y − 200) + 2e-8 (z + 225)²
//! Ez = −8e-6 (z + 225) + 4e-6 x + 1.5e-3 (T − 20)
//! ```
//!
//! with a reversal of +0.5, −0.6, +0.4 µm on X, Y, Z.

use vmc_predict::predictor::ErrorPredictor;

/// Travel of the test machine, mm (that of the reference VMC).
pub const TRAVEL_MM: [[f64; 2]; 3] = [[0.0, 560.0], [0.0, 400.0], [-450.0, 0.0]];

/// The analytic model of the module doc.
#[derive(Debug, Clone)]
pub struct Analytic {
    sensors: Vec<String>,
    /// The reading last observed, °C (NaN before any).
    temp_degc: f64,
    /// Reversal per axis, mm.
    pub shift_mm: [f64; 3],
}

impl Analytic {
    /// A model that has observed nothing yet.
    pub fn new() -> Self {
        Self {
            sensors: vec!["T".into()],
            temp_degc: f64::NAN,
            shift_mm: [0.5e-3, -0.6e-3, 0.4e-3],
        }
    }

    /// The model after observing the reading `temp_degc`.
    pub fn at(temp_degc: f64) -> Self {
        let mut m = Self::new();
        m.observe_readings(0.0, &[temp_degc]);
        m
    }

    /// The formula of the module doc.
    pub fn error_mm(q: [f64; 3], t_degc: f64) -> [f64; 3] {
        let [x, y, z] = q;
        let dt = t_degc - 20.0;
        [
            2e-7 * (x - 280.0).powi(2) + 1e-5 * y - 1e-5 * z
                + 1e-3 * dt
                + 1e-8 * (x - 280.0) * (y - 200.0),
            3e-3 * (x / 150.0).sin() + 5e-6 * (y - 200.0) + 2e-8 * (z + 225.0).powi(2),
            -8e-6 * (z + 225.0) + 4e-6 * x + 1.5e-3 * dt,
        ]
    }
}

impl Default for Analytic {
    fn default() -> Self {
        Self::new()
    }
}

impl ErrorPredictor for Analytic {
    fn sensor_names(&self) -> &[String] {
        &self.sensors
    }

    fn predict_error_mm(&mut self, q_mm: [f64; 3]) -> [f64; 3] {
        Self::error_mm(q_mm, self.temp_degc)
    }

    fn negative_approach_shift_mm(&self) -> [f64; 3] {
        self.shift_mm
    }

    fn observe_readings(&mut self, _time_s: f64, temps_degc: &[f64]) {
        self.temp_degc = temps_degc[0];
    }

    fn observe_spindle_speed(&mut self, _time_s: f64, _rpm: f64) {}

    fn observe_axis_feeds(&mut self, _time_s: f64, _feeds_mm_per_min: [f64; 3]) {}
}
