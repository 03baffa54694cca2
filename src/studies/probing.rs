//! On-machine probing as a duty of its own in the campaign: every `every_s` of the thermal
//! history (from its start, so also right before the measured program when the state's time is
//! a multiple of the interval) the spindle stops, the probe is loaded, reference spheres on the
//! table are touched (on each sphere +X and +Y at its equator, then the tops of all spheres,
//! each touch repeated) and the spindle resumes its duty. The cycle runs in machine time: each
//! touch happens at its own instant ([`run_cycle`]), the thermal history going on with the
//! spindle stopped, because the model's Z residual moves by micrometres within minutes of a
//! spindle stop (the front bearing cools, which no sensor sees in time; see
//! docs/decisions/2026-11-28-probing-drift.md). The touches run on the twin's real, drifted
//! geometry ([`vmc_machine::touch_probe`]); the controller sees only the latched axis positions
//! and evaluates each with its own model at the trip's instant ([`vmc_predict::drift`]),
//! updating its drift estimate ([`DriftField`]) from four spheres not in one plane (three low in
//! the table's corners, one on a tall column) in the order the touches were taken: an offset per
//! axis by default, optionally a gradient per component too; or an offset from one sphere
//! ([`Probing::single_sphere`], the first design, kept to compare).
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
use vmc_machine::touch_probe::{Artefact, ProbeOnTwin, Touch, TouchProbe};
use vmc_machine::twin::{sub_seed, Twin, TwinError};
use vmc_predict::controller::Compensator;
use vmc_predict::drift::{
    artefact_position_mm, ArtefactFix, DriftField, DriftSettingError, FieldSettings, LatchedTouch,
    WithDrift,
};
use vmc_predict::predictor::ErrorPredictor;

use super::calibration::{drive_with, EvalState};

/// Machine time of a probing cycle before its first touch, s: spindle stop (3 s), probe into the
/// spindle (8 s), rapid to the first sphere (3 s).
const CYCLE_LEAD_S: f64 = 14.0;
/// Machine time of a probing cycle after its last touch, s: rapid back (3 s), probe out (8 s),
/// spindle restart (3 s).
const CYCLE_TAIL_S: f64 = 14.0;
/// Machine time of the rapid from one sphere to the next, s.
const SPHERE_TO_SPHERE_S: f64 = 4.0;
/// Machine time of one touch, s: a fast approach over the clearance, a 1 mm back-off, the slow
/// touch at the probing feed, the retract and the move to the next start (the trip half-way).
const TOUCH_TIME_S: f64 = 5.0;
/// Touches per sphere with the field: +X, +Y at the equator, the top (the pre-travel of each
/// direction cancels against the reference, so one side per axis suffices).
pub const FIELD_TOUCHES: [(usize, f64); 3] = [(0, 1.0), (1, 1.0), (2, -1.0)];
/// Touches of the single sphere: ±X, ±Y at the equator, the top.
pub const SPHERE_TOUCHES: [(usize, f64); 5] = [(0, 1.0), (0, -1.0), (1, 1.0), (1, -1.0), (2, -1.0)];
/// Cycles averaged into the artefacts' reference positions by default.
const QUALIFY_CYCLES: usize = 8;
/// Time in which the drift's rate fades, s (when a rate is estimated: `top_passes` 2 and
/// [`FieldSettings::rate_sigma_um_per_min`] set).
const RATE_TAU_S: f64 = 90.0;
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
    /// Repeats of each touch along X and Y (averaged).
    pub repeats: usize,
    /// Repeats of each touch of a top (averaged): the Z drift matters most.
    pub top_repeats: usize,
    /// Passes over the spheres' tops per cycle: 1 (after the touches along X and Y) or 2 (one
    /// before them too, which shows the Z drift's rate within the cycle).
    pub top_passes: usize,
    /// The drift filter's assumptions (random walks, initial σ; the measurement σ follows
    /// from the probe and the repeats, [`Probing::measurement_sigma_um`]).
    pub field: FieldSettings,
    /// Estimate gradients (false: the offset alone, every gradient held at 0).
    pub gradient: bool,
    /// Single gradient terms estimated beside the offset when `gradient` is false, each with a
    /// prior of its own (a regularised field: only the terms named here leave 0).
    pub gradient_terms: Vec<GradientTerm>,
    /// Cycles on the cold machine averaged into the artefacts' reference positions.
    pub qualify_cycles: usize,
}

/// One gradient term of the drift field with its prior: component `component` (0 X, 1 Y, 2 Z)
/// changing along axis `axis`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GradientTerm {
    /// The error component.
    pub component: usize,
    /// The axis it changes along.
    pub axis: usize,
    /// σ before any probing, µm/m.
    pub initial_um_per_m: f64,
    /// Random walk, µm/m per √h.
    pub walk_um_per_m_sqrt_h: f64,
}

impl Probing {
    /// Probing every `every_min` minutes with a typical probe as long as the machine's tool and
    /// four Ø25 mm reference spheres: three on 50 mm stems near the table's X−Y−, X+Y− and X−Y+
    /// corners, one on a 300 mm column at the table's centre; each touched on +X and +Y twice,
    /// then the tops nine times each (the Z drift is what matters, and it moves fastest after
    /// the stop: measured last). The drift is an offset per axis (walk 1 µm/√h, initial σ
    /// 0.7 µm: the model is trusted where it is good); the gradient (`gradient = true`, walks
    /// 2 µm/m/√h, initial σ 2 µm/m) and a fading rate did worse on the development machines
    /// (seeds 21–29), see docs/decisions/2026-11-28-probing-drift.md.
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
            repeats: 2,
            top_repeats: 9,
            top_passes: 1,
            field: default_field_settings(),
            gradient: false,
            gradient_terms: Vec::new(),
            qualify_cycles: QUALIFY_CYCLES,
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
        self.sequence().len()
    }

    /// Repeats of a touch along `axis`.
    fn repeats_of(&self, axis: usize) -> usize {
        if axis == 2 {
            self.top_repeats
        } else {
            self.repeats
        }
    }

    /// The cycle's touches in the order the machine runs them: `(sphere, axis, direction)`,
    /// each repeated. The touches along X and Y, sphere by sphere; then the tops, sphere by
    /// sphere, so that the Z drift is measured last, nearest to the work that follows (the Z
    /// residual moves fastest after the spindle stops: the decision record); with two top
    /// passes the tops are touched before the X and Y touches too.
    pub fn sequence(&self) -> Vec<(usize, usize, f64)> {
        let pass = |z: bool| {
            (0..self.sphere_centres_mm.len()).flat_map(move |i| {
                self.touches
                    .iter()
                    .filter(move |t| (t.0 == 2) == z)
                    .flat_map(move |t| std::iter::repeat_n((i, t.0, t.1), self.repeats_of(t.0)))
            })
        };
        let mut seq: Vec<_> = if self.top_passes >= 2 {
            pass(true).collect()
        } else {
            Vec::new()
        };
        seq.extend(pass(false));
        seq.extend(pass(true));
        seq
    }

    /// Machine time of one cycle, s: lead, touches, moves between spheres, tail.
    pub fn cycle_s(&self) -> f64 {
        let seq = self.sequence();
        let moves = seq.windows(2).filter(|w| w[0].0 != w[1].0).count();
        CYCLE_LEAD_S
            + CYCLE_TAIL_S
            + SPHERE_TO_SPHERE_S * moves as f64
            + seq.len() as f64 * TOUCH_TIME_S
    }

    /// Machine minutes spent probing per hour of duty.
    pub fn cost_min_per_h(&self) -> f64 {
        self.cycle_s() / 60.0 * 3600.0 / self.every_s
    }

    /// σ of one sphere's position along `axis` from one cycle, µm: one touch's σ (the probe's
    /// repeatability and latency, the machine's approach scatter) over the touches along it in
    /// one group; None for an axis not touched.
    pub fn axis_sigma_um(&self, axis: usize) -> Option<f64> {
        let per_touch = touch_sigma_um(&self.probe);
        let n = self.touches.iter().filter(|t| t.0 == axis).count() * self.repeats_of(axis);
        (n > 0).then(|| per_touch / (n as f64).sqrt())
    }

    /// σ of one sphere's position per axis from one cycle, µm, for the axis least touched
    /// (the drift field's default measurement σ; [`Probing::axis_sigma_um`] per axis).
    pub fn measurement_sigma_um(&self) -> f64 {
        (0..3)
            .filter_map(|a| self.axis_sigma_um(a))
            .fold(f64::NAN, f64::max)
    }

    /// The spheres' centroid, mm (the drift field's centre).
    fn centroid_mm(&self) -> [f64; 3] {
        let n = self.sphere_centres_mm.len().max(1) as f64;
        [0, 1, 2].map(|a| self.sphere_centres_mm.iter().map(|c| c[a]).sum::<f64>() / n)
    }

    /// A fresh drift field with these assumptions. With `gradient` false the gradients' prior
    /// and walk are so small that they stay at 0.
    fn filter(&self) -> Result<DriftField, DriftSettingError> {
        let mut f = drift_field(
            &self.field,
            self.centroid_mm(),
            self.gradient,
            [0, 1, 2].map(|a| self.axis_sigma_um(a)),
        )?;
        if !self.gradient {
            for t in &self.gradient_terms {
                f.set_gradient_prior(
                    t.component,
                    t.axis,
                    t.initial_um_per_m,
                    t.walk_um_per_m_sqrt_h,
                )?;
            }
        }
        Ok(f)
    }

    fn artefact(&self, centre_mm: [f64; 3]) -> Artefact {
        Artefact::Sphere {
            centre_mm,
            radius_mm: self.sphere_radius_mm,
        }
    }

    /// The touch along `axis` in direction `sign` onto the sphere at `centre_mm`: its start
    /// from the nominal contact out by the clearance.
    fn touch_of(&self, centre_mm: [f64; 3], axis: usize, sign: f64) -> Touch {
        let rc = self.sphere_radius_mm + self.probe.ball_radius_mm;
        let mut start = centre_mm;
        start[axis] -= sign * (rc + CLEARANCE_MM);
        Touch {
            start_mm: start,
            axis,
            sign,
            max_travel_mm: 2.0 * CLEARANCE_MM,
        }
    }
}

/// The drift filter's assumptions of the default probing: an offset per axis walking by
/// 1 µm/√h from 0 with σ 0.7 µm (the model is trusted where it is good), no rate (touching the
/// tops twice per cycle to see it did not pay on the development machines, the decision
/// record); the gradient's settings apply only when one is estimated. The measurement σ is a
/// placeholder: it follows from the probe and the touches ([`touch_sigma_um`]).
pub fn default_field_settings() -> FieldSettings {
    FieldSettings {
        walk_offset_um_per_sqrt_h: 1.0,
        walk_gradient_um_per_m_sqrt_h: 2.0,
        measurement_sigma_um: 1.0,
        initial_offset_um: 0.7,
        initial_gradient_um_per_m: 2.0,
        rate_sigma_um_per_min: 1e-9,
        rate_tau_s: RATE_TAU_S,
    }
}

/// σ of one touch's latched position along its axis, µm: the probe's repeatability and
/// latency spread, and the machine's non-repeatability of one approach.
pub fn touch_sigma_um(probe: &TouchProbe) -> f64 {
    (probe.sigma_mm() * 1e3).hypot(APPROACH_SIGMA_UM)
}

/// The drift estimator of on-machine probing, as the campaign's cycles and a run's own probe
/// moves use it: a [`DriftField`] with `settings` about `centre_mm`, its gradient held at 0
/// unless `gradient` (prior and walk so small that it stays there), axis `a` measured with σ
/// `axis_sigma_um[a]` µm where given.
///
/// # Errors
/// A setting or σ that is not a finite number > 0.
pub fn drift_field(
    settings: &FieldSettings,
    centre_mm: [f64; 3],
    gradient: bool,
    axis_sigma_um: [Option<f64>; 3],
) -> Result<DriftField, DriftSettingError> {
    let mut s = *settings;
    if !gradient {
        s.initial_gradient_um_per_m = 1e-9;
        s.walk_gradient_um_per_m_sqrt_h = 1e-9;
    }
    let mut f = DriftField::new(centre_mm, &s)?;
    for (a, sigma) in axis_sigma_um.iter().enumerate() {
        if let Some(sigma) = sigma {
            f.set_measurement_sigma_um(a, *sigma)?;
        }
    }
    Ok(f)
}

/// Each sphere's reference position per axis, from the cycle on the cold machine.
#[derive(Debug, Clone, PartialEq)]
pub struct Qualified {
    /// One fix per sphere, in [`Probing::sphere_centres_mm`] order.
    pub spheres: Vec<ArtefactFix>,
}

/// One touch of a cycle as the controller evaluated it at the instant of its trip.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TouchReading {
    /// Index of the sphere in [`Probing::sphere_centres_mm`].
    pub sphere: usize,
    /// Touched axis (0 X, 1 Y, 2 Z).
    pub axis: usize,
    /// Latched axis command, mm.
    pub at_mm: [f64; 3],
    /// The sphere's position along `axis` as the model saw it then, mm: `q + E_pred(q)` (plus
    /// the reversal shift of a negative touch), [`artefact_position_mm`].
    pub position_mm: f64,
    /// Twin time of the trip, s.
    pub time_s: f64,
}

/// Runs one probing cycle on `twin` from now, in machine time: the lead (spindle stopping, probe
/// in), each touch of [`Probing::sequence`] at its own instant with the moves between spheres,
/// the tail; the spindle stands still throughout and `ctrl` follows the readings. Each trip is
/// evaluated at its instant with the model `model(ctrl)` (the model alone, as the controller
/// would log it when the trip latches).
///
/// # Errors
/// A simulation error, or a probe setting that is not usable.
pub fn run_cycle<C: Controller, P: ErrorPredictor>(
    twin: &mut Twin,
    p: &Probing,
    ctrl: &mut C,
    model: fn(&mut C) -> &mut P,
    on_twin: &mut ProbeOnTwin,
) -> Result<Vec<TouchReading>, TwinError> {
    let seq = p.sequence();
    let first = seq.first().map_or([0.0; 3], |t| p.sphere_centres_mm[t.0]);
    park(twin, first, CYCLE_LEAD_S, ctrl)?;
    let mut out = Vec::with_capacity(seq.len());
    let mut last_sphere = seq.first().map(|t| t.0);
    let mut at = first;
    for (sphere, axis, sign) in seq {
        let centre = p.sphere_centres_mm[sphere];
        if last_sphere != Some(sphere) {
            park(twin, centre, SPHERE_TO_SPHERE_S, ctrl)?;
            last_sphere = Some(sphere);
        }
        at = centre;
        park(twin, centre, 0.5 * TOUCH_TIME_S, ctrl)?;
        let trip = on_twin
            .touch(twin, &p.artefact(centre), &p.touch_of(centre, axis, sign))
            .map_err(|e| TwinError::Sensors(format!("probing: {e}")))?;
        if let Some(trip) = trip {
            let latched = LatchedTouch {
                axis_mm: trip.axis_mm,
                axis,
                sign,
            };
            if let Some(position_mm) = artefact_position_mm(model(ctrl), &[latched])[axis] {
                out.push(TouchReading {
                    sphere,
                    axis,
                    at_mm: trip.axis_mm,
                    position_mm,
                    time_s: twin.time_s(),
                });
            }
        }
        park(twin, centre, 0.5 * TOUCH_TIME_S, ctrl)?;
    }
    park(twin, at, CYCLE_TAIL_S, ctrl)?;
    Ok(out)
}

/// One group of a cycle's readings: the successive touches of one sphere along one axis.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Group {
    sphere: usize,
    axis: usize,
    /// Mean latched position, mm.
    at_mm: [f64; 3],
    /// Mean position along the axis as the model saw it, mm.
    position_mm: f64,
    /// Mean trip time, s.
    time_s: f64,
}

/// The readings averaged over each run of successive touches of one sphere along one axis (a
/// sphere's tops in two passes are two groups), in the cycle's order.
fn groups(readings: &[TouchReading]) -> Vec<Group> {
    let mut out: Vec<Vec<&TouchReading>> = Vec::new();
    for r in readings {
        match out.last_mut() {
            Some(g) if g[0].sphere == r.sphere && g[0].axis == r.axis => g.push(r),
            _ => out.push(vec![r]),
        }
    }
    out.into_iter()
        .map(|g| {
            let n = g.len() as f64;
            Group {
                sphere: g[0].sphere,
                axis: g[0].axis,
                at_mm: [0, 1, 2].map(|k| g.iter().map(|r| r.at_mm[k]).sum::<f64>() / n),
                position_mm: g.iter().map(|r| r.position_mm).sum::<f64>() / n,
                time_s: g.iter().map(|r| r.time_s).sum::<f64>() / n,
            }
        })
        .collect()
}

/// The spindle stopped with the axes parked at `at_mm` for `dt_s`, the controller following.
///
/// # Errors
/// A simulation error.
pub fn park(
    twin: &mut Twin,
    at_mm: [f64; 3],
    dt_s: f64,
    ctrl: &mut dyn Controller,
) -> Result<(), TwinError> {
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
    // Qualification is done once and with care: the mean of several cycles, so that its
    // scatter does not become an offset of every later correction.
    let n_spheres = p.sphere_centres_mm.len();
    let mut sum = vec![[0.0; 3]; n_spheres];
    let mut n = vec![[0usize; 3]; n_spheres];
    for _ in 0..p.qualify_cycles.max(1) {
        let readings = run_cycle(
            &mut twin,
            p,
            &mut ctrl,
            Compensator::predictor_mut,
            &mut on_twin,
        )?;
        for g in groups(&readings) {
            sum[g.sphere][g.axis] += g.position_mm;
            n[g.sphere][g.axis] += 1;
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

/// A cycle's drift measurements: per group of successive touches of one sphere along one axis
/// `(time s, component, latched at mm, drift mm)`, the drift being the sphere's reference minus
/// its position as the model saw it, in the cycle's order.
pub fn drift_measurements(
    readings: &[TouchReading],
    fix: &Qualified,
) -> Vec<(f64, usize, [f64; 3], f64)> {
    groups(readings)
        .into_iter()
        .filter_map(|g| {
            let sphere = fix.spheres.get(g.sphere)?;
            let mut position = [None; 3];
            position[g.axis] = Some(g.position_mm);
            let drift = sphere.drift_mm(position)[g.axis]?;
            Some((g.time_s, g.axis, g.at_mm, drift))
        })
        .collect()
}

/// One probing cycle on `twin`: the touches, evaluated with the model alone, update the drift
/// field of `ctrl` in the order they were taken.
fn probe_cycle<P: ErrorPredictor>(
    twin: &mut Twin,
    p: &Probing,
    fix: &Qualified,
    ctrl: &mut Compensator<WithDrift<P, DriftField>>,
    on_twin: &mut ProbeOnTwin,
) -> Result<(), TwinError> {
    let readings = run_cycle(twin, p, ctrl, |c| c.predictor_mut().inner_mut(), on_twin)?;
    let filter = ctrl.predictor_mut().filter_mut();
    for (time_s, axis, at_mm, drift_mm) in drift_measurements(&readings, fix) {
        filter.update(time_s, &[(axis, at_mm, drift_mm)]);
    }
    Ok(())
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
    Drift(#[from] DriftSettingError),
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

#[cfg(test)]
mod tests;
