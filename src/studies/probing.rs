//! On-machine probing as a duty of its own in the campaign: every `every_s` of the thermal
//! history (from its start, so also right before the measured program when the state's time is
//! a multiple of the interval) the spindle stops, the probe is loaded, a reference sphere on the
//! table is touched five times (±X and ±Y at its equator, Z on its top, each touch twice) and the spindle
//! resumes its duty. The touches run on the twin's real, drifted geometry
//! ([`vmc_machine::touch_probe`]); the controller sees only the latched axis positions and
//! evaluates them with its own model ([`vmc_predict::drift`]), updating its drift filter.
//!
//! The artefact's reference position is qualified once per machine and model: the same cycle on
//! a cold machine (every node at the ambient's 20 °C, a noise stream of its own) with the model
//! following the readings from there. The cycle's machine time is charged: the duty's clock
//! pauses while the probe works, and the spindle stands still meanwhile (which the thermal
//! history feels).

use vmc_machine::machine::MachineSpec;
use vmc_machine::sim::{self, Controller};
use vmc_machine::thermal::Activity;
use vmc_machine::touch_probe::{Artefact, ProbeOnTwin, Touch, TouchProbe, Trip};
use vmc_machine::twin::{sub_seed, Twin, TwinError};
use vmc_predict::controller::Compensator;
use vmc_predict::drift::{artefact_position_mm, ArtefactFix, DriftFilter, LatchedTouch, WithDrift};
use vmc_predict::predictor::ErrorPredictor;

use super::calibration::{drive_with, EvalState};

/// Machine time of one probing cycle besides the touches, s: spindle stop and restart (2 × 3 s),
/// probe in and out of the spindle (2 × 8 s), rapids to the sphere and back (2 × 3 s).
const CYCLE_OVERHEAD_S: f64 = 28.0;
/// Machine time of one touch, s: a fast approach over the clearance, a 1 mm back-off, the slow
/// touch at the probing feed, the retract and the move to the next start.
const TOUCH_TIME_S: f64 = 5.0;
/// Touches per cycle: ±X, ±Y at the equator, the top.
const TOUCHES: [(usize, f64); 5] = [(0, 1.0), (0, -1.0), (1, 1.0), (1, -1.0), (2, -1.0)];
/// Cycles averaged into the artefact's reference position.
const QUALIFY_CYCLES: usize = 8;
/// Touches repeated per direction in one cycle (averaged).
const REPEATS: usize = 2;
/// Clearance of each touch's start from the nominal contact, mm.
const CLEARANCE_MM: f64 = 5.0;

/// Probing in the campaign: interval, probe, artefact and the drift filter's assumptions.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Probing {
    /// Interval between probing cycles, s.
    pub every_s: f64,
    /// The probe.
    pub probe: TouchProbe,
    /// Reference sphere centre, workpiece coordinates, mm.
    pub sphere_centre_mm: [f64; 3],
    /// Its radius, mm.
    pub sphere_radius_mm: f64,
    /// The drift filter's random walk, µm per √h.
    pub walk_sigma_um_per_sqrt_h: f64,
}

impl Probing {
    /// Probing every `every_min` minutes with a typical probe as long as the machine's tool, a
    /// Ø25 mm reference sphere on a 50 mm stem near the table's X−Y− corner, and a drift walk of
    /// 3 µm/√h (the largest residual the model leaves changes by a few µm per hour).
    pub fn every(spec: &MachineSpec, every_min: f64) -> Self {
        let min = spec.axes.travel_min_mm;
        Probing {
            every_s: every_min * 60.0,
            probe: TouchProbe::typical(-spec.tool.offset_mm[2]),
            sphere_centre_mm: [min[0] + 40.0, min[1] + 40.0, min[2] + 73.0],
            sphere_radius_mm: 12.5,
            walk_sigma_um_per_sqrt_h: 3.0,
        }
    }

    /// Machine time of one cycle, s.
    pub fn cycle_s(&self) -> f64 {
        CYCLE_OVERHEAD_S + (REPEATS * TOUCHES.len()) as f64 * TOUCH_TIME_S
    }

    /// Machine minutes spent probing per hour of duty.
    pub fn cost_min_per_h(&self) -> f64 {
        self.cycle_s() / 60.0 * 3600.0 / self.every_s
    }

    /// σ of one cycle's artefact position per axis, µm: one touch's σ, averaged over the two
    /// opposite touches in X and Y (the top alone in Z: the larger, used for all three).
    pub fn measurement_sigma_um(&self) -> f64 {
        self.probe.sigma_mm() * 1e3
    }

    /// A fresh drift filter with these assumptions.
    fn filter(&self) -> DriftFilter {
        DriftFilter::new(
            self.walk_sigma_um_per_sqrt_h,
            self.measurement_sigma_um(),
            self.walk_sigma_um_per_sqrt_h,
        )
        .expect("positive settings")
    }

    fn artefact(&self) -> Artefact {
        Artefact::Sphere {
            centre_mm: self.sphere_centre_mm,
            radius_mm: self.sphere_radius_mm,
        }
    }

    /// The five touches' starts, from the nominal contact out by the clearance.
    fn touches(&self) -> Vec<Touch> {
        let rc = self.sphere_radius_mm + self.probe.ball_radius_mm;
        TOUCHES
            .iter()
            .flat_map(|t| std::iter::repeat_n(*t, REPEATS))
            .map(|(axis, sign)| {
                let mut start = self.sphere_centre_mm;
                start[axis] -= sign * (rc + CLEARANCE_MM);
                Touch {
                    start_mm: start,
                    axis,
                    sign,
                    max_travel_mm: 2.0 * CLEARANCE_MM,
                }
            })
            .collect()
    }
}

/// One cycle's touches on `twin` at its present state, as the controller latched them.
fn touch_all(
    p: &Probing,
    twin: &mut Twin,
    on_twin: &mut ProbeOnTwin,
) -> Result<Vec<LatchedTouch>, TwinError> {
    let mut out = Vec::new();
    for t in p.touches() {
        let trip: Option<Trip> = on_twin
            .touch(twin, &p.artefact(), &t)
            .map_err(|e| TwinError::Sensors(format!("probing: {e}")))?;
        if let Some(trip) = trip {
            out.push(LatchedTouch {
                axis_mm: trip.axis_mm,
                axis: t.axis,
                sign: t.sign,
            });
        }
    }
    Ok(out)
}

/// The spindle stopped with the axes parked at the sphere for `dt_s`, the controller following.
fn park(
    twin: &mut Twin,
    p: &Probing,
    dt_s: f64,
    ctrl: &mut dyn Controller,
) -> Result<(), TwinError> {
    let mut left = dt_s;
    while left > 1e-9 {
        let dt = left.min(1.0);
        let activity = Activity {
            spindle_rpm: 0.0,
            axis_pos_mm: p.sphere_centre_mm,
            axis_speed_mm_per_min: [0.0; 3],
            coolant: false,
        };
        sim::step(twin, dt, &activity, Some(ctrl))?;
        left -= dt;
    }
    Ok(())
}

/// The artefact's reference position for machine `seed` under `model`: one cycle on a cold
/// twin (its own noise stream) with the model following the readings.
pub fn qualify<P: ErrorPredictor + Clone>(
    spec: &MachineSpec,
    seed: u64,
    p: &Probing,
    model: &P,
) -> Result<ArtefactFix, TwinError> {
    let noise = sub_seed(seed, 7000);
    let mut twin = Twin::with_noise_seed(spec, seed, noise)?;
    let mut ctrl = Compensator::new(model.clone());
    sim::hand_over(&twin, Some(&mut ctrl));
    let mut on_twin = ProbeOnTwin::new(p.probe, sub_seed(noise, 1))
        .map_err(|e| TwinError::Sensors(format!("probing: {e}")))?;
    // Qualification is done once and with care: the mean of QUALIFY_CYCLES cycles, so that
    // its scatter does not become an offset of every later correction.
    let mut sum = [0.0; 3];
    let mut n = [0usize; 3];
    for _ in 0..QUALIFY_CYCLES {
        park(&mut twin, p, 0.5 * p.cycle_s(), &mut ctrl)?;
        let touches = touch_all(p, &mut twin, &mut on_twin)?;
        let position = artefact_position_mm(ctrl.predictor_mut(), &touches);
        for a in 0..3 {
            if let Some(v) = position[a] {
                sum[a] += v;
                n[a] += 1;
            }
        }
    }
    Ok(ArtefactFix {
        reference_mm: [0, 1, 2].map(|a| (n[a] > 0).then(|| sum[a] / n[a] as f64)),
    })
}

/// Drives `twin` through `state`'s history with probing cycles every [`Probing::every_s`] of
/// duty (cycle time 0 included, and the state's time when it is a multiple), `ctrl` following
/// the readings and updating its drift filter from each cycle. Returns the number of cycles.
pub fn drive_probed<P: ErrorPredictor>(
    twin: &mut Twin,
    state: &EvalState,
    p: &Probing,
    fix: &ArtefactFix,
    ctrl: &mut Compensator<WithDrift<P>>,
    probe_seed: u64,
) -> Result<usize, TwinError> {
    let mut on_twin = ProbeOnTwin::new(p.probe, probe_seed)
        .map_err(|e| TwinError::Sensors(format!("probing: {e}")))?;
    sim::hand_over(twin, Some(ctrl));
    // Twin time of cycle time 0; moves on by each probing cycle's time (the duty pauses).
    let mut t0_s = twin.time_s();
    let mut duty_s = 0.0;
    let mut cycles = 0;
    loop {
        // A probing cycle at this duty time.
        park(twin, p, 0.5 * p.cycle_s(), ctrl)?;
        let touches = touch_all(p, twin, &mut on_twin)?;
        let model = ctrl.predictor_mut();
        let position = artefact_position_mm(model.inner_mut(), &touches);
        let now = twin.time_s();
        model.filter_mut().update(now, fix.drift_mm(position));
        park(twin, p, 0.5 * p.cycle_s(), ctrl)?;
        t0_s += p.cycle_s();
        cycles += 1;
        if duty_s >= state.at_s - 1e-9 {
            break;
        }
        let to_s = (duty_s + p.every_s).min(state.at_s);
        // The duty resumes where it paused; its clock is cycle time.
        drive_with(twin, &state.cycle, t0_s, to_s, 1.0, Some(ctrl))?;
        duty_s = to_s;
        if (state.at_s - duty_s).abs() < 1e-9 && ((state.at_s / p.every_s).fract()).abs() > 1e-9 {
            // The state's time is not a multiple of the interval: no cycle right before it.
            break;
        }
    }
    Ok(cycles)
}

/// A compensator with a fresh drift filter of `p` around `model`.
pub fn probed_compensator<P: ErrorPredictor>(
    model: P,
    p: &Probing,
    sensor_names: &[String],
) -> Result<Compensator<WithDrift<P>>, vmc_predict::predictor::PredictError> {
    Compensator::for_machine(WithDrift::new(model, p.filter()), sensor_names)
}

#[allow(clippy::too_many_arguments)]
/// [`super::calibration::run_at_state`] with probing: the history of `state` with probing
/// cycles ([`drive_probed`]), then `plan` compensated by `ctrl` with the drift it estimated.
/// Returns the measurement points.
pub fn run_at_state_probed<P: ErrorPredictor>(
    spec: &MachineSpec,
    machine_seed: u64,
    noise_seed: u64,
    state: &EvalState,
    plan: &vmc_machine::motion::Plan,
    p: &Probing,
    fix: &ArtefactFix,
    ctrl: &mut Compensator<WithDrift<P>>,
) -> Result<Vec<sim::PointRecord>, sim::SimError> {
    let mut twin = Twin::with_noise_seed(spec, machine_seed, noise_seed)?;
    state.cycle.prepare(&mut twin)?;
    drive_probed(&mut twin, state, p, fix, ctrl, sub_seed(noise_seed, 9))?;
    let mut log = sim::CollectPoints::default();
    sim::execute(
        &mut twin,
        plan,
        &sim::SimConfig::default().with_thermal_part(true),
        Some(ctrl),
        &mut log,
    )?;
    Ok(log.points)
}
