//! Virtual instruments: what a metrologist measures on the machine, with the
//! instruments' noise and step sizes, while the machine keeps heating or cooling.
//!
//! Instruments are the one place besides the twin itself that touches truth: like real ones,
//! they observe the physical machine. What they produce is a [`Record`] of the calibration
//! dataset — the only form in which a predictor ever sees their findings.
//!
//! Idealisations (stated so users can judge them):
//! - the 6-DOF interferometer is aligned to the machine frame and reads the six motion errors of
//!   the swept axis at its reference point (Abbe offsets of the setup removed), plus noise:
//!   linear σ = a + b·L (L = distance from the sweep start), straightness σ, angular σ;
//! - laser sweeps are bidirectional over the campaign (ISO 230-2's forward and backward runs
//!   through the same targets): successive sweeps of an axis alternate between a forward run
//!   from the travel minimum to the maximum and a backward run from the maximum to the minimum,
//!   so a measurement block takes the same time as a forward-only one; each record carries its
//!   approach direction (`dir` = 1 forward, −1 backward). The positioning reading includes the
//!   axis's reversal (real motion, which the two directions separate) and its
//!   non-repeatability (which nothing can predict);
//! - the volumetric grid approaches every point positively on every axis (`dir` = 1), as a
//!   unidirectional tracker procedure would;
//! - the 5-probe spindle test reads the spindle's own drifts (the axis errors at the test pose are
//!   separated with the laser data), plus probe noise, with the spindle running (ISO 230-3), so
//!   it logs continuously through the duty;
//! - the squareness measurement (laser with optical square) reads the three angles plus angular
//!   noise;
//! - the volumetric instrument (laser tracker) reads the error vector at a point, plus linear noise.
//!
//! Each reading takes `laser_point_s` of machine time with the spindle stopped, during which
//! the thermal network keeps evolving; temperatures are logged with every reading.

use rand::rngs::StdRng;
use rand::SeedableRng;
use rand_distr::{Distribution, Normal};

use crate::machine::InstrumentSpec;
use crate::thermal::Activity;
use crate::twin::{Twin, TwinError};
use vmc_predict::dataset::{Instrument, Record};

/// The instrument set of one campaign, with its own noise generator.
pub struct Instruments {
    spec: InstrumentSpec,
    travel_min_mm: [f64; 3],
    travel_max_mm: [f64; 3],
    rng: StdRng,
    /// Laser sweeps run so far per axis (even: the next one runs forward).
    sweeps_done: [usize; 3],
}

impl Instruments {
    /// Instruments of `twin`'s machine description, noise drawn from `seed`.
    pub fn new(twin: &Twin, seed: u64) -> Self {
        let spec = twin.spec();
        Instruments {
            spec: spec.instruments.clone(),
            travel_min_mm: spec.axes.travel_min_mm,
            travel_max_mm: spec.axes.travel_max_mm,
            rng: StdRng::seed_from_u64(seed),
            sweeps_done: [0; 3],
        }
    }

    fn gauss(&mut self, sigma: f64) -> f64 {
        if sigma <= 0.0 {
            return 0.0;
        }
        Normal::new(0.0, sigma)
            .map(|n| n.sample(&mut self.rng))
            .unwrap_or(0.0)
    }

    /// Positions of a sweep of `axis`: from the travel minimum in laser steps, the last step
    /// shortened to end at the maximum.
    pub fn sweep_positions_mm(&self, axis: usize) -> Vec<f64> {
        let (lo, hi) = (self.travel_min_mm[axis], self.travel_max_mm[axis]);
        let step = self.spec.laser_step_mm[axis];
        let mut v = Vec::new();
        let mut x = lo;
        while x < hi - 1e-9 {
            v.push(x);
            x += step;
        }
        v.push(hi);
        v
    }

    /// Lets `duration_s` of machine time pass at axis position `q_mm`, spindle stopped, axis
    /// `moving_axis` travelling `step_mm` during it (a measurement in progress).
    fn dwell(
        &self,
        twin: &mut Twin,
        q_mm: [f64; 3],
        moving_axis: Option<(usize, f64)>,
        duration_s: f64,
    ) -> Result<(), TwinError> {
        let mut speed = [0.0; 3];
        if let Some((a, step_mm)) = moving_axis {
            speed[a] = step_mm / duration_s * 60.0;
        }
        let activity = Activity {
            spindle_rpm: 0.0,
            axis_pos_mm: q_mm,
            axis_speed_mm_per_min: speed,
            coolant: false,
        };
        twin.advance(duration_s, &activity)
    }

    #[allow(clippy::too_many_arguments)]
    fn record(
        &self,
        twin: &Twin,
        cycle: &str,
        t0_s: f64,
        instrument: Instrument,
        q_mm: [f64; 3],
        values: [f64; 6],
        dir: i8,
    ) -> Record {
        Record {
            cycle: cycle.to_string(),
            time_s: twin.time_s() - t0_s,
            instrument,
            pos_mm: q_mm,
            values,
            temps_degc: twin.sensor_readings().values_degc,
            dir,
            spindle_rpm: None,
            axis_feed_mm_per_min: None,
        }
    }

    /// A 6-DOF laser sweep of `axis` with the other axes at `park_mm`: the axis's first,
    /// third, … sweep runs forward from the travel minimum to the maximum (`dir` 1), its second,
    /// fourth, … backward through the same positions (`dir` −1). Appends one record per
    /// position. `t0_s` is the cycle's start (twin time).
    pub fn laser_sweep(
        &mut self,
        twin: &mut Twin,
        axis: usize,
        park_mm: [f64; 3],
        cycle: &str,
        t0_s: f64,
        out: &mut Vec<Record>,
    ) -> Result<(), TwinError> {
        let mut positions = self.sweep_positions_mm(axis);
        let start_mm = positions[0];
        let dir = if self.sweeps_done[axis].is_multiple_of(2) {
            1
        } else {
            -1
        };
        self.sweeps_done[axis] += 1;
        if dir < 0 {
            positions.reverse();
        }
        self.laser_run(
            twin, axis, park_mm, &positions, start_mm, dir, cycle, t0_s, out,
        )
    }

    /// One run of a laser sweep through `positions` approached in direction `dir` (±1); the
    /// laser's linear noise grows with the distance from `start_mm` (where it was zeroed).
    #[allow(clippy::too_many_arguments)]
    fn laser_run(
        &mut self,
        twin: &mut Twin,
        axis: usize,
        park_mm: [f64; 3],
        positions: &[f64],
        start_mm: f64,
        dir: i8,
        cycle: &str,
        t0_s: f64,
        out: &mut Vec<Record>,
    ) -> Result<(), TwinError> {
        let mut prev = positions[0];
        for &s in positions {
            let mut q = park_mm;
            q[axis] = s;
            self.dwell(
                twin,
                q,
                Some((axis, (s - prev).abs())),
                self.spec.laser_point_s,
            )?;
            // Each target is reached moving in the run's direction (the first target with an
            // overrun, as ISO 230-2 does).
            let v = f64::from(dir);
            twin.note_motion([0, 1, 2].map(|a| if a == axis { v } else { 0.0 }));
            prev = s;
            let approach = twin.draw_approach_mm();
            let mut e = twin.elementary_errors(q).axes[axis];
            e.lin_mm[axis] += approach[axis];
            let dist_m = (s - start_mm).abs() * 1e-3;
            let lin_sigma = self.spec.laser_noise_um + self.spec.laser_noise_um_per_m * dist_m;
            let mut values = [0.0; 6];
            for c in 0..3 {
                let sigma = if c == axis {
                    lin_sigma
                } else {
                    self.spec.straightness_noise_um
                };
                values[c] = e.lin_mm[c] * 1e3 + self.gauss(sigma);
                values[3 + c] = e.ang_rad[c] * 1e6 + self.gauss(self.spec.angular_noise_urad);
            }
            let r = self.record(twin, cycle, t0_s, Instrument::laser(axis), q, values, dir);
            out.push(r);
        }
        Ok(())
    }

    /// The 5-probe spindle test at `q_mm`: δx, δy, δz (µm), εx, εy (µrad), read now. As in
    /// ISO 230-3 the probes read a test mandrel while the spindle runs, so the reading takes no
    /// machine time and does not interrupt the duty.
    pub fn spindle_test(
        &mut self,
        twin: &Twin,
        q_mm: [f64; 3],
        cycle: &str,
        t0_s: f64,
        out: &mut Vec<Record>,
    ) {
        let d = twin.elementary_errors(q_mm).spindle;
        let p = self.spec.probe_noise_um;
        // Tilts come from two radial probes 100 mm apart: σ_tilt = √2·σ_probe / 100 mm.
        let tilt_sigma_urad = std::f64::consts::SQRT_2 * p / 100.0 * 1e3;
        let values = [
            d.lin_mm[0] * 1e3 + self.gauss(p),
            d.lin_mm[1] * 1e3 + self.gauss(p),
            d.lin_mm[2] * 1e3 + self.gauss(p),
            d.tilt_rad[0] * 1e6 + self.gauss(tilt_sigma_urad),
            d.tilt_rad[1] * 1e6 + self.gauss(tilt_sigma_urad),
            f64::NAN,
        ];
        let r = self.record(twin, cycle, t0_s, Instrument::Spindle, q_mm, values, 1);
        out.push(r);
    }

    /// The 5-probe spindle test logged at `q_mm` right after the spindle stops (ISO 230-3's
    /// stopped phase): a reading every `every_s` for `duration_s` of machine time, axes parked.
    /// The drift's fast transient after a stop (bearings and nose cooling) is what a diagonal
    /// test run right after a duty sees, so the calibration must observe it.
    #[allow(clippy::too_many_arguments)]
    pub fn spindle_stop_log(
        &mut self,
        twin: &mut Twin,
        q_mm: [f64; 3],
        duration_s: f64,
        every_s: f64,
        cycle: &str,
        t0_s: f64,
        out: &mut Vec<Record>,
    ) -> Result<(), TwinError> {
        if every_s.is_nan() || every_s <= 0.0 {
            return Ok(());
        }
        let mut t = 0.0;
        while t + every_s <= duration_s + 1e-9 {
            self.dwell(twin, q_mm, None, every_s)?;
            t += every_s;
            self.spindle_test(twin, q_mm, cycle, t0_s, out);
        }
        Ok(())
    }

    /// Squareness with a laser and optical square: α_yz, α_xz, α_xy (µrad) in rx, ry, rz.
    pub fn squareness(
        &mut self,
        twin: &mut Twin,
        q_mm: [f64; 3],
        cycle: &str,
        t0_s: f64,
        out: &mut Vec<Record>,
    ) -> Result<(), TwinError> {
        self.dwell(twin, q_mm, None, self.spec.laser_point_s)?;
        let s = twin.elementary_errors(q_mm).squareness;
        let a = self.spec.angular_noise_urad;
        let values = [
            f64::NAN,
            f64::NAN,
            f64::NAN,
            s.yz_rad * 1e6 + self.gauss(a),
            s.xz_rad * 1e6 + self.gauss(a),
            s.xy_rad * 1e6 + self.gauss(a),
        ];
        let r = self.record(twin, cycle, t0_s, Instrument::Squareness, q_mm, values, 1);
        out.push(r);
        Ok(())
    }

    /// Volumetric error measured at each point (laser tracker), µm.
    pub fn volumetric(
        &mut self,
        twin: &mut Twin,
        points_mm: &[[f64; 3]],
        cycle: &str,
        t0_s: f64,
        out: &mut Vec<Record>,
    ) -> Result<(), TwinError> {
        for &p in points_mm {
            self.dwell(twin, p, None, self.spec.laser_point_s)?;
            // Every point approached positively on every axis (unidirectional procedure).
            twin.note_motion([1.0; 3]);
            let approach = twin.draw_approach_mm();
            let e = twin.tool_error_mm(p, p, approach);
            let sigma = self.spec.laser_noise_um + self.spec.laser_noise_um_per_m * 0.5;
            let values = [
                e.x * 1e3 + self.gauss(sigma),
                e.y * 1e3 + self.gauss(sigma),
                e.z * 1e3 + self.gauss(sigma),
                f64::NAN,
                f64::NAN,
                f64::NAN,
            ];
            let r = self.record(twin, cycle, t0_s, Instrument::Volumetric, p, values, 1);
            out.push(r);
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::machine::MachineSpec;

    #[test]
    fn the_stopped_phase_spindle_log_reads_every_interval_while_time_passes() {
        let spec = MachineSpec::reference();
        let mut twin = Twin::new(&spec, 1).unwrap();
        let mut inst = Instruments::new(&twin, 7);
        let mut out = Vec::new();
        let q = [280.0, 200.0, -225.0];
        inst.spindle_stop_log(&mut twin, q, 180.0, 30.0, "c", 0.0, &mut out)
            .unwrap();
        let times: Vec<f64> = out.iter().map(|r| r.time_s).collect();
        assert_eq!(times, vec![30.0, 60.0, 90.0, 120.0, 150.0, 180.0]);
        assert!(out.iter().all(|r| r.instrument == Instrument::Spindle
            && r.pos_mm == q
            && r.values[..5].iter().all(|v| v.is_finite())));
        // A zero or NaN interval logs nothing and lets no time pass.
        let t = twin.time_s();
        inst.spindle_stop_log(&mut twin, q, 180.0, 0.0, "c", 0.0, &mut out)
            .unwrap();
        inst.spindle_stop_log(&mut twin, q, 180.0, f64::NAN, "c", 0.0, &mut out)
            .unwrap();
        assert_eq!((out.len(), twin.time_s()), (6, t));
    }
}
