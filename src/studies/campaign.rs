//! The whole study in one call: calibration campaign → training of the three
//! predictors → every face and body diagonal under held-out thermal states, without and with
//! compensation → report.
//!
//! The predictors come from `vmc-predict` and see only the calibration dataset and, in the loop,
//! the held sensor readings (a [`Compensator`] is the loop's [`vmc_machine::sim::Controller`]).
//! Evaluation states are atypical cycles that never enter the calibration data, and evaluation
//! noise (sensors, repeatability, reversal) is drawn from other seeds than the calibration's: the
//! same machine on another day.
//!
//! Prediction metrics compare, at each measurement point, the true uncompensated error E(p) with
//! the error the controller compensated for, `p − q` (= E_pred(q) at the fixed point), over the
//! three components pooled. MAPE is mean|e| / mean|y| (robust to small |y|).

use rayon::prelude::*;
use thiserror::Error;

use crate::predict::controller::Compensator;
use crate::predict::dataset::Dataset;
use crate::predict::predictor::{
    self, ErrorPredictor, ModelKind, PredictError, Settings, TrainSummary,
};
use crate::predict::provenance::TrainedOn;
use crate::studies::calibration::{self, CampaignConfig, EvalState, ThermalCycle};
use crate::studies::probing::{self, Probing};
use vmc_machine::machine::MachineSpec;
use vmc_machine::motion::Plan;
use vmc_machine::program::{self, ProgramError};
use vmc_machine::sim::SimError;
use vmc_machine::twin::{sub_seed, Twin, TwinError};

pub use report::{
    headline, median, replay, run_report, write_run_row, write_run_table, write_run_table_foot,
    write_run_table_head, CampaignReport, Headline, HeadlineBuilder, PlannedCycle, RunPasses,
    RunReport, PREDICTORS, WARM_RUN_MIN_THERMAL_UM,
};
pub use summary::{
    write_campaign_summary, write_report_json, write_summary, ReportHeader, SeedResults, Summary,
    SummaryBuilder,
};
pub use vmc_machine::program::DIAGONALS;

pub mod fleet;
pub mod fleet_png;
pub mod histogram;
pub mod order_stats;
mod report;
mod summary;

/// A campaign that could not run.
#[derive(Debug, Error)]
pub enum EvalError {
    /// Twin problem.
    #[error(transparent)]
    Twin(#[from] TwinError),
    /// Simulation problem.
    #[error(transparent)]
    Sim(#[from] SimError),
    /// Training or model problem.
    #[error(transparent)]
    Predict(#[from] PredictError),
    /// A diagonal program failed to plan.
    #[error(transparent)]
    Program(#[from] ProgramError),
    /// A compensator with a drift field that could not be built.
    #[error(transparent)]
    Probed(#[from] probing::ProbedCompensatorError),
}

/// Drives `twin` through `state`'s cycle up to the state (1 s thermal steps, cycle time 0 at
/// the twin's start) with `predictor` following every reading, as the controller does before
/// a test, and gives the predictor back (its history features at the state). For diagnosis
/// examples that compare predictions with the truth at a state.
///
/// # Errors
/// Twin errors.
pub fn follow_to_state<P: ErrorPredictor>(
    twin: &mut Twin,
    state: &EvalState,
    predictor: P,
) -> Result<P, TwinError> {
    twin.set_ambient(state.cycle.ambient.clone())?;
    let mut follow = Compensator::new(predictor);
    calibration::drive_with(twin, &state.cycle, 0.0, state.at_s, 1.0, Some(&mut follow))?;
    Ok(follow.into_inner())
}

/// Seed of the evaluation noise (sensors, repeatability, reversal) of the run of diagonal
/// `diagonal_index` at state `state_index` on machine `seed`: never the calibration's streams
/// (those use 1000 + k).
pub fn eval_noise_seed(seed: u64, state_index: usize, diagonal_index: usize) -> u64 {
    sub_seed(seed, 5000 + (state_index * 100 + diagonal_index) as u64)
}

/// Receives the progress of a campaign in work units (see [`run_campaign_with_progress`]).
pub trait CampaignProgress: Sync {
    /// `units` more work units are planned.
    fn add_total(&self, _units: u64) {}
    /// `units` work units are done; `what` says what is running now.
    fn advance(&self, _units: u64, _what: &str) {}
}

/// Progress that goes nowhere.
impl CampaignProgress for () {}

/// Work units of the campaign steps (rough relative costs measured on the reference machine).
pub mod units {
    /// Calibration campaign of one seed.
    pub const CALIBRATION: u64 = 40;
    /// Training one predictor.
    pub const TRAINING: u64 = 20;
    /// One evaluated run (one diagonal at one state, compensated).
    pub const RUN: u64 = 1;
}

/// Plans the campaign's diagonal programs for a machine (from its home position).
pub fn diagonal_plans(spec: &MachineSpec) -> Result<Vec<(&'static str, Plan)>, EvalError> {
    DIAGONALS
        .iter()
        .map(|(name, text)| {
            let file = format!("trajectories/diag_{}.ngc", name.to_lowercase());
            Ok((
                *name,
                program::plan_source(text, &file, spec, spec.axes.home_mm)?,
            ))
        })
        .collect()
}

/// Evaluates one predictor on every diagonal and state for one seed. Runs are independent and
/// execute in parallel (rayon); each has its own seeded twin, so the result is identical to a
/// single-threaded run and comes back in (state, diagonal) order.
pub fn evaluate_predictor<P: ErrorPredictor + Clone + Send + Sync>(
    spec: &MachineSpec,
    seed: u64,
    kind: ModelKind,
    predictor: &P,
    states: &[EvalState],
    plans: &[(&str, Plan)],
) -> Result<Vec<RunReport>, EvalError> {
    evaluate_predictor_with_progress(spec, seed, kind, predictor, states, plans, &())
}

/// [`evaluate_predictor`], reporting each finished run to `progress`.
pub fn evaluate_predictor_with_progress<P: ErrorPredictor + Clone + Send + Sync>(
    spec: &MachineSpec,
    seed: u64,
    kind: ModelKind,
    predictor: &P,
    states: &[EvalState],
    plans: &[(&str, Plan)],
    progress: &dyn CampaignProgress,
) -> Result<Vec<RunReport>, EvalError> {
    evaluate_predictor_probed(spec, seed, kind, predictor, states, plans, None, progress)
}

/// [`evaluate_predictor_with_progress`], with a probing duty in every run when `probing` is
/// given ([`probing::run_at_state_probed`]; the artefact qualified once on the cold machine).
#[allow(clippy::too_many_arguments)]
pub fn evaluate_predictor_probed<P: ErrorPredictor + Clone + Send + Sync>(
    spec: &MachineSpec,
    seed: u64,
    kind: ModelKind,
    predictor: &P,
    states: &[EvalState],
    plans: &[(&str, Plan)],
    probing: Option<&Probing>,
    progress: &dyn CampaignProgress,
) -> Result<Vec<RunReport>, EvalError> {
    let sensor_names: Vec<String> = spec.sensors.iter().map(|s| s.name.clone()).collect();
    let fix = match probing {
        Some(p) => Some(probing::qualify(spec, seed, p, predictor)?),
        None => None,
    };
    let jobs: Vec<(usize, usize)> = (0..states.len())
        .flat_map(|si| (0..plans.len()).map(move |di| (si, di)))
        .collect();
    let results: Vec<Result<Option<RunReport>, EvalError>> = jobs
        .par_iter()
        .map(|&(si, di)| {
            let (state, (diag, plan)) = (&states[si], &plans[di]);
            let noise = eval_noise_seed(seed, si, di);
            let points = match (probing, &fix) {
                (Some(p), Some(fix)) => {
                    let mut ctrl =
                        probing::probed_compensator(predictor.clone(), p, &sensor_names)?;
                    probing::run_at_state_probed(spec, seed, noise, state, plan, p, fix, &mut ctrl)?
                }
                _ => {
                    let mut ctrl = Compensator::for_machine(predictor.clone(), &sensor_names)?;
                    calibration::run_at_state(spec, seed, noise, state, plan, Some(&mut ctrl))?
                }
            };
            progress.advance(
                units::RUN,
                &format!("seed {seed}: {} {diag} at {}", kind.name(), state.name),
            );
            Ok(run_report(kind, diag, &state.name, seed, &points))
        })
        .collect();
    let mut out = Vec::with_capacity(results.len());
    for r in results {
        out.extend(r?);
    }
    Ok(out)
}

/// Time constant of the ambient history feature, s: the order of the column's and bed's thermal
/// time constants (capacity / convection ≈ 7–9 h on the reference machine), the slow structure
/// that follows the air and that the present readings see only at a few points.
pub const AMBIENT_HISTORY_TAU_S: f64 = 8.0 * 3600.0;

/// `settings` with the history feature of the machine's ambient sensors (those on the
/// `ambient` node, which the operator knows measure the air): each network also sees the
/// ambient reading minus its low-pass filter with [`AMBIENT_HISTORY_TAU_S`]. A machine without
/// an ambient sensor gets no history feature. See `vmc_predict::history` and
/// docs/decisions/2026-11-23-ambient-history-feature.md for how this was chosen and what it gives.
pub fn with_ambient_history(settings: Settings, spec: &MachineSpec) -> Settings {
    let (taus, ambient) = on_node(
        &settings,
        spec,
        vmc_machine::thermal::AMBIENT_NODE,
        AMBIENT_HISTORY_TAU_S,
    );
    Settings {
        history_taus_s: taus,
        history_sensors: ambient,
        ..settings
    }
}

/// The model's sensors (`settings.sensors`, all of `spec`'s when empty) on thermal node `node`,
/// with the time constants of a history feature of them: `[tau_s]`, or none without such a
/// sensor.
fn on_node(
    settings: &Settings,
    spec: &MachineSpec,
    node: &str,
    tau_s: f64,
) -> (Vec<f64>, Vec<String>) {
    let names: Vec<String> = spec
        .sensors
        .iter()
        .filter(|s| s.node == node)
        .map(|s| s.name.clone())
        .filter(|n| settings.sensors.is_empty() || settings.sensors.contains(n))
        .collect();
    let taus = if names.is_empty() {
        Vec::new()
    } else {
        vec![tau_s]
    };
    (taus, names)
}

/// Node of the thermal model whose sensors get the spindle-only rate feature
/// ([`with_spindle_nose_rate`]).
pub const SPINDLE_NOSE_NODE: &str = "spindle_nose";

/// Time constant of the spindle-only history feature of the spindle nose sensors, s.
pub const SPINDLE_NOSE_TAU_S: f64 = 300.0;

/// `settings` with a spindle-only history feature of the machine's spindle nose sensors (those
/// on the [`SPINDLE_NOSE_NODE`] node, a location the operator knows): the spindle part also sees
/// the nose reading minus its low-pass filter with [`SPINDLE_NOSE_TAU_S`], about τ times its
/// rate. Why: the spindle's axial growth follows the front bearing, which no sensor touches; the
/// heat it passes to the nose shows as the nose reading's rate, so the rate tells how much
/// warmer than the nose the bearing is. The axis parts do not get it (as an input of every
/// network it made things worse). Chosen on the selection-only states of machine seeds 21–23,
/// never on the held-out runs: docs/decisions/2026-11-23-spindle-nose-rate.md.
pub fn with_spindle_nose_rate(settings: Settings, spec: &MachineSpec) -> Settings {
    let (taus, nose) = on_node(&settings, spec, SPINDLE_NOSE_NODE, SPINDLE_NOSE_TAU_S);
    Settings {
        spindle_history_taus_s: taus,
        spindle_history_sensors: nose,
        ..settings
    }
}

/// The predictor settings that run for a machine (`campaign`, `train`, `select-sensors`):
/// [`Settings::default`] with the history features that need to know where the machine's
/// sensors sit ([`with_history_features`]). The knowledge crate knows sensor names only, so
/// this default lives with the machine.
pub trait ForMachine {
    /// The settings for the sensors of `spec`.
    fn for_machine(spec: &MachineSpec) -> Self;
}

impl ForMachine for Settings {
    fn for_machine(spec: &MachineSpec) -> Self {
        with_history_features(Settings::default(), spec)
    }
}

/// `settings` with both history features of [`ForMachine::for_machine`] for the sensors of `spec`
/// (restricted to `settings.sensors` when that is not empty) and the axes' commanded feeds
/// ([`with_axis_feeds`]).
pub fn with_history_features(settings: Settings, spec: &MachineSpec) -> Settings {
    with_axis_feeds(with_spindle_nose_rate(
        with_ambient_history(settings, spec),
        spec,
    ))
}

/// Time constant of the axes' commanded-feed features, s: the order of a ballscrew's thermal
/// time constant (a segment's capacity over its losses, about half an hour to an hour).
/// Chosen on selection-only states: docs/decisions/2026-11-25-commanded-axis-feeds.md.
pub const AXIS_FEED_TAU_S: f64 = 3600.0;

/// `settings` with the axes' commanded feeds as inputs of every part of the hybrid (one filter,
/// [`AXIS_FEED_TAU_S`]) unless it names its own filters: no sensor sits on the screws, and
/// the controller knows what it commanded.
pub fn with_axis_feeds(settings: Settings) -> Settings {
    if settings.axis_feed_taus_s.is_empty() {
        Settings {
            axis_feed_taus_s: vec![AXIS_FEED_TAU_S],
            ..settings
        }
    } else {
        settings
    }
}

/// The calibration plan's validation cycles: two combined duties, one with a speed change and
/// one under an ambient ramp. Every cycle that isolates a heat source (an axis alone, the
/// spindle sweep, the cold and warm shops) stays in the training data: held out, what it alone
/// shows would be missing from the model. Chosen on selection-only states (never the held-out
/// ones): docs/decisions/2026-11-24-calibration-plan.md.
pub const PLAN_VALIDATION_CYCLES: [&str; 2] = ["cal_4000_8000rpm", "cal_day_drift"];

/// `settings` fitted to the dataset `data`:
/// - [`PLAN_VALIDATION_CYCLES`] as validation cycles when it names none and `data` has them all
///   (a dataset of the calibration plan); otherwise the automatic choice of
///   [`Settings::val_fraction`];
/// - no axis-feed features when a record of `data` lacks the axes' feeds (a dataset logged
///   without them): the model then does without, see [`uses_axis_feeds`].
pub fn fit_to_data(settings: Settings, data: &Dataset) -> Settings {
    let has = |name: &str| data.records.iter().any(|r| r.cycle == name);
    let mut settings = settings;
    if settings.val_cycles.is_empty() && PLAN_VALIDATION_CYCLES.iter().all(|c| has(c)) {
        settings.val_cycles = PLAN_VALIDATION_CYCLES.map(String::from).to_vec();
    }
    if !uses_axis_feeds(data) {
        settings.axis_feed_taus_s.clear();
        settings.axis_feed_own_axis = false;
    }
    settings
}

/// Whether every record of `data` carries the axes' commanded feeds (the dataset's
/// `x_feed_mm_per_min` … columns), so that a model can learn from them.
pub fn uses_axis_feeds(data: &Dataset) -> bool {
    !data.records.is_empty()
        && data
            .records
            .iter()
            .all(|r| r.axis_feed_mm_per_min.is_some())
}

/// Calibration, training and evaluation for one machine seed.
struct SeedResult {
    training: Vec<(u64, TrainSummary)>,
    runs: Vec<RunReport>,
    models: TrainedModels,
}

fn campaign_for_seed(
    spec: &MachineSpec,
    seed: u64,
    settings: &Settings,
    cal_cycles: &[ThermalCycle],
    plans: &[(&str, Plan)],
    probing: Option<&Probing>,
    progress: &dyn CampaignProgress,
) -> Result<SeedResult, EvalError> {
    let geometry = spec.geometry();
    progress.advance(0, &format!("seed {seed}: calibration campaign"));
    let data = calibration::calibrate(spec, cal_cycles, &CampaignConfig::new(seed))?;
    let s = fit_to_data(
        Settings {
            seed,
            ..settings.clone()
        },
        &data,
    );
    progress.advance(units::CALIBRATION, &format!("seed {seed}: training"));
    let (hybrid, hs) = predictor::train_hybrid(&data, &geometry, &s)?;
    progress.advance(units::TRAINING, &format!("seed {seed}: training"));
    let (volumetric, vs) = predictor::train_volumetric(&data, &geometry, &s)?;
    progress.advance(units::TRAINING, &format!("seed {seed}: training"));
    let (linear, ls) = predictor::train_linear(&data, &geometry, &s)?;
    let trained_on = |sensors: &[String]| TrainedOn {
        machine: data.origin.clone(),
        inputs: data.input_ranges(sensors),
    };
    let mut hybrid_on = trained_on(hybrid.sensor_names());
    hybrid_on.inputs.axis_feeds = predictor::feed_ranges(&data, &s.axis_feed_taus_s);
    let trained_on = [
        hybrid_on,
        trained_on(volumetric.sensor_names()),
        trained_on(linear.sensor_names()),
    ];
    progress.advance(units::TRAINING, &format!("seed {seed}: evaluation"));
    let states = calibration::evaluation_states(spec, seed);
    let mut runs = evaluate_predictor_probed(
        spec,
        seed,
        ModelKind::Hybrid,
        &hybrid,
        &states,
        plans,
        probing,
        progress,
    )?;
    runs.extend(evaluate_predictor_probed(
        spec,
        seed,
        ModelKind::Volumetric,
        &volumetric,
        &states,
        plans,
        probing,
        progress,
    )?);
    runs.extend(evaluate_predictor_probed(
        spec,
        seed,
        ModelKind::Linear,
        &linear,
        &states,
        plans,
        probing,
        progress,
    )?);
    Ok(SeedResult {
        training: vec![(seed, hs), (seed, vs), (seed, ls)],
        runs,
        models: TrainedModels {
            seed,
            trained_on,
            hybrid,
            volumetric,
            linear,
        },
    })
}

/// Runs the full campaign for `seeds`: calibrate, train the three predictors, evaluate.
pub fn run_campaign(
    spec: &MachineSpec,
    seeds: &[u64],
    settings: &Settings,
) -> Result<(CampaignReport, Vec<TrainedModels>), EvalError> {
    run_campaign_with_progress(spec, seeds, settings, &())
}

/// [`run_campaign`], reporting its progress (work units of [`units`]) to `progress`.
pub fn run_campaign_with_progress(
    spec: &MachineSpec,
    seeds: &[u64],
    settings: &Settings,
    progress: &dyn CampaignProgress,
) -> Result<(CampaignReport, Vec<TrainedModels>), EvalError> {
    run_campaign_with_cycles(
        spec,
        seeds,
        settings,
        &ThermalCycle::calibration_plan(spec),
        progress,
    )
}

/// [`run_campaign_with_progress`] calibrated on `cal_cycles` instead of the typical set
/// (scaling studies, a user's own calibration plan).
pub fn run_campaign_with_cycles(
    spec: &MachineSpec,
    seeds: &[u64],
    settings: &Settings,
    cal_cycles: &[ThermalCycle],
    progress: &dyn CampaignProgress,
) -> Result<(CampaignReport, Vec<TrainedModels>), EvalError> {
    run_campaign_probed(spec, seeds, settings, cal_cycles, None, progress)
}

/// [`run_campaign_with_cycles`] with a probing duty in every held-out run when `probing` is
/// given (see [`probing`]); without it, the same campaign.
pub fn run_campaign_probed(
    spec: &MachineSpec,
    seeds: &[u64],
    settings: &Settings,
    cal_cycles: &[ThermalCycle],
    probing: Option<&Probing>,
    progress: &dyn CampaignProgress,
) -> Result<(CampaignReport, Vec<TrainedModels>), EvalError> {
    let cal_cycles = cal_cycles.to_vec();
    let plans = diagonal_plans(spec)?;
    let n_runs = (calibration::evaluation_states(spec, 0).len() * plans.len()) as u64;
    progress.add_total(
        seeds.len() as u64 * (units::CALIBRATION + 3 * units::TRAINING + 3 * n_runs * units::RUN),
    );
    let header = campaign_header(spec, seeds, settings, &cal_cycles);
    let mut report = CampaignReport {
        machine: header.machine,
        calibration_cycles: header.calibration_cycles,
        calibration_plan: header.calibration_plan,
        evaluation_states: header.evaluation_states,
        training: Vec::new(),
        runs: Vec::new(),
        hybrid_uses_spindle_speed: header.hybrid_uses_spindle_speed,
    };
    // Seeds are independent: run them in parallel, collect in seed order.
    let per_seed: Vec<Result<SeedResult, EvalError>> = seeds
        .par_iter()
        .map(|&seed| {
            campaign_for_seed(spec, seed, settings, &cal_cycles, &plans, probing, progress)
        })
        .collect();
    let mut models = Vec::new();
    for r in per_seed {
        let r = r?;
        report.training.extend(r.training);
        report.runs.extend(r.runs);
        models.push(r.models);
    }
    Ok((report, models))
}

/// The header of the report of a campaign over `seeds` (the held-out states are named after
/// the first seed's), whichever part of the seeds is run.
pub fn campaign_header(
    spec: &MachineSpec,
    seeds: &[u64],
    settings: &Settings,
    cal_cycles: &[ThermalCycle],
) -> ReportHeader {
    ReportHeader {
        machine: spec.machine.name.clone(),
        calibration_cycles: cal_cycles.iter().map(|c| c.name.clone()).collect(),
        calibration_plan: cal_cycles
            .iter()
            .map(|c| PlannedCycle {
                name: c.name.clone(),
                hours: c.duration_s() / 3600.0,
                purpose: c.purpose.clone(),
            })
            .collect(),
        evaluation_states: seeds
            .first()
            .map(|&s| {
                calibration::evaluation_states(spec, s)
                    .iter()
                    .map(|s| s.name.clone())
                    .collect()
            })
            .unwrap_or_default(),
        hybrid_uses_spindle_speed: settings.uses_spindle_speed(),
    }
}

/// The three predictors trained for one seed.
pub struct TrainedModels {
    /// Machine seed.
    pub seed: u64,
    /// What each model was trained on, in [`PREDICTORS`] order.
    pub trained_on: [TrainedOn; 3],
    /// The study's hybrid predictor.
    pub hybrid: predictor::HybridPredictor,
    /// Direct volumetric MLP.
    pub volumetric: predictor::VolumetricPredictor,
    /// Linear regression baseline.
    pub linear: predictor::LinearPredictor,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn history_features_go_to_the_sensors_on_their_nodes_and_only_those_in_the_model() {
        let spec = MachineSpec::reference();
        let s = Settings::for_machine(&spec);
        // Each feature is on (one time constant) for the sensor on its node.
        assert_eq!(s.history_sensors, vec!["Amb".to_string()]);
        assert_eq!(s.history_taus_s.len(), 1);
        assert_eq!(s.spindle_history_sensors, vec!["BYB".to_string()]);
        assert_eq!(s.spindle_history_taus_s.len(), 1);
        // A model without the nose sensor gets no spindle feature, and keeps the ambient one.
        let others: Vec<String> = spec
            .sensors
            .iter()
            .map(|s| s.name.clone())
            .filter(|n| n != "BYB")
            .collect();
        let s = with_history_features(
            Settings {
                sensors: others,
                ..Settings::default()
            },
            &spec,
        );
        assert!(s.spindle_history_taus_s.is_empty() && s.spindle_history_sensors.is_empty());
        assert_eq!(s.history_sensors, vec!["Amb".to_string()]);
        // A machine without an ambient sensor gets no ambient feature.
        let mut no_air = spec.clone();
        no_air
            .sensors
            .retain(|s| s.node != vmc_machine::thermal::AMBIENT_NODE);
        let s = Settings::for_machine(&no_air);
        assert!(s.history_taus_s.is_empty() && s.history_sensors.is_empty());
        assert_eq!(s.spindle_history_sensors, vec!["BYB".to_string()]);
    }
}
