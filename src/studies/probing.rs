//! On-machine probing as a duty of its own in the campaign: every `every_s` of the thermal
//! history (from its start, so also right before the measured program when the state's time is
//! a multiple of the interval) the spindle stops, the probe is loaded, reference spheres on the
//! table are touched (on each sphere +X and +Y at its equator and Z on its top, each touch
//! repeated) and the spindle resumes its duty. The touches run on the twin's real, drifted
//! geometry ([`vmc_machine::touch_probe`]); the controller sees only the latched axis positions
//! and evaluates them with its own model ([`vmc_predict::drift`]), updating its drift estimate
//! ([`DriftField`]) from four spheres not in one plane (three low in the table's corners, one
//! on a tall column): an offset per axis by default, optionally a gradient per component too;
//! or an offset from one sphere ([`Probing::single_sphere`], the first design, kept to compare).
//!
//! Each sphere's reference position is qualified once per machine and model: the same cycle on
//! a cold machine (every node at the ambient's 20 °C, a noise stream of its own) with the model
//! following the readings from there; the probe's pre-travel and mean latency, and the spheres'
//! own positions, cancel against it. The columns are taken as thermally stable (low-expansion
//! material): the twin moves the spheres with the table only. The cycle's machine time is
//! charged: the duty's clock pauses while the probe works, and the spindle stands still
//! meanwhile (which the thermal history feels).

use vmc_machine::machine::MachineSpec;
use vmc_machine::sim::{self, Controller};
use vmc_machine::thermal::Activity;
use vmc_machine::touch_probe::{Artefact, ProbeOnTwin, Touch, TouchProbe, Trip};
use vmc_machine::twin::{sub_seed, Twin, TwinError};
use vmc_predict::controller::Compensator;
use vmc_predict::drift::{
    artefact_position_mm, ArtefactFix, DriftField, FieldSettings, LatchedTouch, WithDrift,
};
use vmc_predict::predictor::ErrorPredictor;

use super::calibration::{drive_with, EvalState};

/// Machine time of one probing cycle besides the touches, s: spindle stop and restart (2 × 3 s),
/// probe in and out of the spindle (2 × 8 s), rapids to the first sphere and back (2 × 3 s).
const CYCLE_OVERHEAD_S: f64 = 28.0;
/// Machine time of the rapid from one sphere to the next, s.
const SPHERE_TO_SPHERE_S: f64 = 4.0;
/// Machine time of one touch, s: a fast approach over the clearance, a 1 mm back-off, the slow
/// touch at the probing feed, the retract and the move to the next start.
const TOUCH_TIME_S: f64 = 5.0;
/// Touches per sphere with the field: +X, +Y at the equator, the top (the pre-travel of each
/// direction cancels against the reference, so one side per axis suffices).
pub const FIELD_TOUCHES: [(usize, f64); 3] = [(0, 1.0), (1, 1.0), (2, -1.0)];
/// Touches of the single sphere: ±X, ±Y at the equator, the top.
pub const SPHERE_TOUCHES: [(usize, f64); 5] = [(0, 1.0), (0, -1.0), (1, 1.0), (1, -1.0), (2, -1.0)];
/// Cycles averaged into the artefacts' reference positions.
const QUALIFY_CYCLES: usize = 8;
/// Clearance of each touch's start from the nominal contact, mm.
const CLEARANCE_MM: f64 = 5.0;
/// The machine's non-repeatability of one approach as the controller's maker states it, µm (σ
/// per axis): it scatters every touch beside the probe's own repeatability.
const APPROACH_SIGMA_UM: f64 = 0.3;

/// Probing in the campaign: interval, probe, artefacts and the drift filter's assumptions.
#[derive(Debug, Clone, PartialEq)]
pub struct Probing {
    /// Interval between probing cycles, s.
    pub every_s: f64,
    /// The probe.
    pub probe: TouchProbe,
    /// Reference sphere centres, workpiece coordinates, mm.
    pub sphere_centres_mm: Vec<[f64; 3]>,
    /// Their radius, mm.
    pub sphere_radius_mm: f64,
    /// Touches per sphere: axis and direction.
    pub touches: Vec<(usize, f64)>,
    /// Repeats of each touch (averaged).
    pub repeats: usize,
    /// The drift filter's assumptions (random walks, initial σ; the measurement σ follows
    /// from the probe and the repeats, [`Probing::measurement_sigma_um`]).
    pub field: FieldSettings,
    /// Estimate gradients (false: the offset alone, every gradient held at 0).
    pub gradient: bool,
}

impl Probing {
    /// Probing every `every_min` minutes with a typical probe as long as the machine's tool and
    /// four Ø25 mm reference spheres: three on 50 mm stems near the table's X−Y−, X+Y− and X−Y+
    /// corners, one on a 300 mm column at the table's centre; each touched on +X, +Y and its
    /// top, each touch three times. The drift is an offset per axis (walk 1 µm/√h, initial σ
    /// 0.7 µm: the model is trusted where it is good); the gradient (`gradient = true`, walks
    /// 2 µm/m/√h, initial σ 2 µm/m) did worse on the development machines (seeds 21–23), see
    /// docs/decisions/2026-11-28-probing-drift.md.
    pub fn every(spec: &MachineSpec, every_min: f64) -> Self {
        let (min, max) = (spec.axes.travel_min_mm, spec.axes.travel_max_mm);
        let low_z = min[2] + 73.0;
        let mid = |a: usize| 0.5 * (min[a] + max[a]);
        let mut p = Probing {
            every_s: every_min * 60.0,
            probe: TouchProbe::typical(-spec.tool.offset_mm[2]),
            sphere_centres_mm: vec![
                [min[0] + 40.0, min[1] + 40.0, low_z],
                [max[0] - 40.0, min[1] + 40.0, low_z],
                [min[0] + 40.0, max[1] - 40.0, low_z],
                [mid(0), mid(1), low_z + 250.0],
            ],
            sphere_radius_mm: 12.5,
            touches: FIELD_TOUCHES.to_vec(),
            repeats: 3,
            field: FieldSettings {
                walk_offset_um_per_sqrt_h: 1.0,
                walk_gradient_um_per_m_sqrt_h: 2.0,
                measurement_sigma_um: 1.0,
                initial_offset_um: 0.7,
                initial_gradient_um_per_m: 2.0,
            },
            gradient: false,
        };
        p.field.measurement_sigma_um = p.measurement_sigma_um();
        p
    }

    /// The first design, kept to compare: one sphere near the table's X−Y− corner touched on
    /// ±X, ±Y and its top, each twice, and a per-axis offset alone.
    pub fn single_sphere(spec: &MachineSpec, every_min: f64) -> Self {
        let mut p = Probing::every(spec, every_min);
        p.sphere_centres_mm.truncate(1);
        p.touches = SPHERE_TOUCHES.to_vec();
        p.gradient = false;
        p.field.measurement_sigma_um = p.measurement_sigma_um();
        p
    }

    /// Touches per cycle.
    pub fn touches_per_cycle(&self) -> usize {
        self.sphere_centres_mm.len() * self.touches.len() * self.repeats
    }

    /// Machine time of one cycle, s.
    pub fn cycle_s(&self) -> f64 {
        CYCLE_OVERHEAD_S
            + SPHERE_TO_SPHERE_S * self.sphere_centres_mm.len().saturating_sub(1) as f64
            + self.touches_per_cycle() as f64 * TOUCH_TIME_S
    }

    /// Machine minutes spent probing per hour of duty.
    pub fn cost_min_per_h(&self) -> f64 {
        self.cycle_s() / 60.0 * 3600.0 / self.every_s
    }

    /// σ of one sphere's position per axis from one cycle, µm: one touch's σ (the probe's
    /// repeatability and latency, the machine's approach scatter) over the touches of the axis
    /// least touched.
    pub fn measurement_sigma_um(&self) -> f64 {
        let per_touch = (self.probe.sigma_mm() * 1e3).hypot(APPROACH_SIGMA_UM);
        let least = (0..3)
            .map(|a| self.touches.iter().filter(|t| t.0 == a).count())
            .filter(|&n| n > 0)
            .min()
            .unwrap_or(1);
        per_touch / ((least * self.repeats.max(1)) as f64).sqrt()
    }

    /// The spheres' centroid, mm (the drift field's centre).
    fn centroid_mm(&self) -> [f64; 3] {
        let n = self.sphere_centres_mm.len().max(1) as f64;
        [0, 1, 2].map(|a| self.sphere_centres_mm.iter().map(|c| c[a]).sum::<f64>() / n)
    }

    /// A fresh drift field with these assumptions. With `gradient` false the gradients' prior
    /// and walk are so small that they stay at 0.
    fn filter(&self) -> Result<DriftField, vmc_predict::drift::DriftSettingError> {
        let mut s = self.field;
        if !self.gradient {
            s.initial_gradient_um_per_m = 1e-9;
            s.walk_gradient_um_per_m_sqrt_h = 1e-9;
        }
        DriftField::new(self.centroid_mm(), &s)
    }

    fn artefact(&self, centre_mm: [f64; 3]) -> Artefact {
        Artefact::Sphere {
            centre_mm,
            radius_mm: self.sphere_radius_mm,
        }
    }

    /// The touches' starts on the sphere at `centre_mm`, from the nominal contact out by the
    /// clearance.
    fn touches_of(&self, centre_mm: [f64; 3]) -> Vec<Touch> {
        let rc = self.sphere_radius_mm + self.probe.ball_radius_mm;
        self.touches
            .iter()
            .flat_map(|t| std::iter::repeat_n(*t, self.repeats))
            .map(|(axis, sign)| {
                let mut start = centre_mm;
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

/// Each sphere's reference position per axis, from the cycle on the cold machine.
#[derive(Debug, Clone, PartialEq)]
pub struct Qualified {
    /// One fix per sphere, in [`Probing::sphere_centres_mm`] order.
    pub spheres: Vec<ArtefactFix>,
}

/// One cycle's touches on `twin` at its present state, as the controller latched them, per
/// sphere.
fn touch_all(
    p: &Probing,
    twin: &mut Twin,
    on_twin: &mut ProbeOnTwin,
) -> Result<Vec<Vec<LatchedTouch>>, TwinError> {
    let mut out = Vec::new();
    for &centre in &p.sphere_centres_mm {
        let mut latched = Vec::new();
        for t in p.touches_of(centre) {
            let trip: Option<Trip> = on_twin
                .touch(twin, &p.artefact(centre), &t)
                .map_err(|e| TwinError::Sensors(format!("probing: {e}")))?;
            if let Some(trip) = trip {
                latched.push(LatchedTouch {
                    axis_mm: trip.axis_mm,
                    axis: t.axis,
                    sign: t.sign,
                });
            }
        }
        out.push(latched);
    }
    Ok(out)
}

/// Where the touches of each axis were latched, mean axis position (mm): where that axis's
/// measurement of the drift applies.
fn latched_at_mm(touches: &[LatchedTouch]) -> [Option<[f64; 3]>; 3] {
    [0, 1, 2].map(|a| {
        let of: Vec<_> = touches.iter().filter(|t| t.axis == a).collect();
        (!of.is_empty()).then(|| {
            [0, 1, 2].map(|k| of.iter().map(|t| t.axis_mm[k]).sum::<f64>() / of.len() as f64)
        })
    })
}

/// The spindle stopped with the axes parked at the first sphere for `dt_s`, the controller
/// following.
fn park(
    twin: &mut Twin,
    p: &Probing,
    dt_s: f64,
    ctrl: &mut dyn Controller,
) -> Result<(), TwinError> {
    let at_mm = p.sphere_centres_mm.first().copied().unwrap_or([0.0; 3]);
    let mut left = dt_s;
    while left > 1e-9 {
        let dt = left.min(1.0);
        let activity = Activity {
            spindle_rpm: 0.0,
            axis_pos_mm: at_mm,
            axis_speed_mm_per_min: [0.0; 3],
            coolant: false,
        };
        sim::step(twin, dt, &activity, Some(ctrl))?;
        left -= dt;
    }
    Ok(())
}

/// The spheres' reference positions for machine `seed` under `model`: cycles on a cold twin
/// (its own noise stream) with the model following the readings, averaged.
///
/// # Errors
/// A simulation error, or a probe setting that is not usable.
pub fn qualify<P: ErrorPredictor + Clone>(
    spec: &MachineSpec,
    seed: u64,
    p: &Probing,
    model: &P,
) -> Result<Qualified, TwinError> {
    let noise = sub_seed(seed, 7000);
    let mut twin = Twin::with_noise_seed(spec, seed, noise)?;
    let mut ctrl = Compensator::new(model.clone());
    sim::hand_over(&twin, Some(&mut ctrl));
    let mut on_twin = ProbeOnTwin::new(p.probe, sub_seed(noise, 1))
        .map_err(|e| TwinError::Sensors(format!("probing: {e}")))?;
    // Qualification is done once and with care: the mean of QUALIFY_CYCLES cycles, so that
    // its scatter does not become an offset of every later correction.
    let n_spheres = p.sphere_centres_mm.len();
    let mut sum = vec![[0.0; 3]; n_spheres];
    let mut n = vec![[0usize; 3]; n_spheres];
    for _ in 0..QUALIFY_CYCLES {
        park(&mut twin, p, 0.5 * p.cycle_s(), &mut ctrl)?;
        let touches = touch_all(p, &mut twin, &mut on_twin)?;
        for (i, t) in touches.iter().enumerate() {
            let position = artefact_position_mm(ctrl.predictor_mut(), t);
            for a in 0..3 {
                if let Some(v) = position[a] {
                    sum[i][a] += v;
                    n[i][a] += 1;
                }
            }
        }
    }
    Ok(Qualified {
        spheres: (0..n_spheres)
            .map(|i| ArtefactFix {
                reference_mm: [0, 1, 2].map(|a| (n[i][a] > 0).then(|| sum[i][a] / n[i][a] as f64)),
            })
            .collect(),
    })
}

/// One probing cycle on `twin`: the touches, evaluated with the model alone, update the drift
/// field of `ctrl`.
fn probe_cycle<P: ErrorPredictor>(
    twin: &mut Twin,
    p: &Probing,
    fix: &Qualified,
    ctrl: &mut Compensator<WithDrift<P, DriftField>>,
    on_twin: &mut ProbeOnTwin,
) -> Result<(), TwinError> {
    park(twin, p, 0.5 * p.cycle_s(), ctrl)?;
    let touches = touch_all(p, twin, on_twin)?;
    let model = ctrl.predictor_mut();
    let mut measurements = Vec::new();
    for (t, sphere) in touches.iter().zip(&fix.spheres) {
        let drift = sphere.drift_mm(artefact_position_mm(model.inner_mut(), t));
        let at = latched_at_mm(t);
        for a in 0..3 {
            if let (Some(d), Some(at)) = (drift[a], at[a]) {
                measurements.push((a, at, d));
            }
        }
    }
    model.filter_mut().update(twin.time_s(), &measurements);
    park(twin, p, 0.5 * p.cycle_s(), ctrl)
}

/// Drives `twin` through `state`'s history with probing cycles every [`Probing::every_s`] of
/// duty (cycle time 0 included, and the state's time when it is a multiple), `ctrl` following
/// the readings and updating its drift field from each cycle. Returns the number of cycles.
///
/// # Errors
/// A simulation error, or a probe setting that is not usable.
pub fn drive_probed<P: ErrorPredictor>(
    twin: &mut Twin,
    state: &EvalState,
    p: &Probing,
    fix: &Qualified,
    ctrl: &mut Compensator<WithDrift<P, DriftField>>,
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
        probe_cycle(twin, p, fix, ctrl, &mut on_twin)?;
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

/// Why a compensator with a drift field could not be built.
#[derive(Debug, thiserror::Error)]
pub enum ProbedCompensatorError {
    /// A drift setting that is not usable.
    #[error(transparent)]
    Drift(#[from] vmc_predict::drift::DriftSettingError),
    /// Sensors the model does not know.
    #[error(transparent)]
    Predict(#[from] crate::predict::predictor::PredictError),
}

/// A compensator with a fresh drift field of `p` around `model`.
///
/// # Errors
/// A drift setting that is not usable, or sensors the model does not know.
pub fn probed_compensator<P: ErrorPredictor>(
    model: P,
    p: &Probing,
    sensor_names: &[String],
) -> Result<Compensator<WithDrift<P, DriftField>>, ProbedCompensatorError> {
    Ok(Compensator::for_machine(
        WithDrift::new(model, p.filter()?),
        sensor_names,
    )?)
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
    fix: &Qualified,
    ctrl: &mut Compensator<WithDrift<P, DriftField>>,
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
