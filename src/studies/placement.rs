//! Where to put the thermometers.
//!
//! The study chose 11 of many candidate locations from a thermo-mechanical simulation campaign.
//! This module does the same on the twin, in three steps:
//! 1. **Candidates**: every thermal-network node, plus ambient, read *as a sensor would* — the
//!    machine's own thermistor model (noise σ, lag τ, 0.0625 °C quantisation, taken from its
//!    first non-ambient sensor) — never the node temperatures themselves.
//! 2. **Selection data**: the virtual calibration campaign (laser sweeps, squareness, 5-probe
//!    spindle test; [`crate::studies::calibration::calibrate`]) over *varied* scenarios: the typical
//!    calibration cycles (constant and progressive duty, axis-heavy, slow ambient drift, ambient
//!    steps) plus four selection-only cycles ([`validation_cycles`]: random duty, ambient steps,
//!    a sinusoidal ambient swing, a restart), drawn from their own seed stream. None of the
//!    held-out evaluation states is among them.
//! 3. **Proposals**: correlation clustering into K clusters, one sensor per cluster by relevance
//!    or by greedy selection on a linear model's leave-one-cycle-out error, and the linear
//!    forward selection ([`crate::predict::selection`], where the rules are stated).
//! 4. **Validation**: each proposal trains the hybrid predictor on the typical cycles of the
//!    selection campaign and compensates every diagonal at the selection-validation states
//!    ([`validation_states`]: the selection-only cycles after 2, 4 and 6 h, and a cold machine;
//!    the selection's machine seed). The proposal with the lowest quadratic mean over runs of
//!    RMS |E| after compensation is chosen. Only selection scenarios are used to choose.
//!
//! The comparison then calibrates the hybrid predictor on the typical cycles with each sensor
//! set — the selected K, the study's default locations, K random locations (several seeded
//! draws), all candidates — and runs every diagonal under the held-out states with compensation,
//! on machine seeds of the user's choice (the selection itself uses one seed).

use rand::rngs::StdRng;
use rand::seq::SliceRandom;
use rand::SeedableRng;
use serde::{Deserialize, Serialize};

use crate::predict::dataset::Dataset;
use crate::predict::predictor::{self, ModelKind, Settings};
use crate::predict::selection::{self, Selection, SelectionConfig, SelectionError};
use crate::studies::calibration::{self, CampaignConfig, EvalState, ThermalCycle};
use crate::studies::campaign::{self, EvalError, RunReport};
use vmc_machine::machine::{MachineError, MachineSpec};
use vmc_machine::sensors::SensorSpec;
use vmc_machine::thermal::{AmbientProfile, AMBIENT_NODE};
use vmc_machine::twin::sub_seed;

mod compare;
mod report;
pub use compare::{compare_seeds, summarise_comparison, SeedRuns};
pub use report::{
    report_json, report_json_with, selection_json, write_comparison, write_report,
    write_selection_part,
};

/// Settings of the placement study.
#[derive(Debug, Clone)]
pub struct PlacementConfig {
    /// Machine seed of the selection campaign (default 1).
    pub seed: u64,
    /// The selection procedure's settings (K = `selection.count`, default 11).
    pub selection: SelectionConfig,
    /// Machine seeds of the comparison (default `[1]`; empty = no comparison).
    pub compare_seeds: Vec<u64>,
    /// Random sets of K drawn for the comparison (default 3).
    pub random_draws: usize,
    /// Predictor training settings (default: [`Settings::default`]).
    pub settings: Settings,
}

impl Default for PlacementConfig {
    fn default() -> Self {
        Self {
            seed: 1,
            selection: SelectionConfig::default(),
            compare_seeds: vec![1],
            random_draws: 3,
            settings: Settings::default(),
        }
    }
}

/// Why the study failed.
#[derive(Debug, thiserror::Error)]
pub enum PlacementError {
    /// Campaign, training or evaluation.
    #[error(transparent)]
    Eval(#[from] EvalError),
    /// The selection procedure.
    #[error(transparent)]
    Selection(#[from] SelectionError),
    /// A sensor set does not fit the machine.
    #[error(transparent)]
    Machine(#[from] MachineError),
    /// The machine has no sensor to copy the thermistor model from.
    #[error("the machine file has no sensor on a thermal node to take the thermistor model (noise, lag, resolution) from")]
    NoTemplate,
}

/// The sensor that reads `node` with the template's thermistor model; named after the node.
fn sensor_on(template: &SensorSpec, node: &str) -> SensorSpec {
    SensorSpec {
        name: node.to_string(),
        node: node.to_string(),
        ..template.clone()
    }
}

/// Every node of the machine's thermal network, plus ambient, as a candidate sensor.
///
/// # Errors
/// [`PlacementError::NoTemplate`] when no sensor of the machine sits on a node.
pub fn candidate_sensors(spec: &MachineSpec) -> Result<Vec<SensorSpec>, PlacementError> {
    let template = spec
        .sensors
        .iter()
        .find(|s| s.node != AMBIENT_NODE)
        .ok_or(PlacementError::NoTemplate)?;
    let ambient = spec
        .sensors
        .iter()
        .find(|s| s.node == AMBIENT_NODE)
        .unwrap_or(template);
    Ok(std::iter::once(sensor_on(ambient, AMBIENT_NODE))
        .chain(
            spec.thermal
                .nodes
                .iter()
                .map(|n| sensor_on(template, &n.name)),
        )
        .collect())
}

/// The candidates of a study: every one of [`candidate_sensors`], or those on the nodes `only`
/// (ambient always, as the cold reference).
///
/// # Errors
/// As [`candidate_sensors`].
pub fn candidates_among(
    spec: &MachineSpec,
    only: Option<&[String]>,
) -> Result<Vec<SensorSpec>, PlacementError> {
    let mut candidates = candidate_sensors(spec)?;
    if let Some(only) = only {
        candidates.retain(|c| c.node == AMBIENT_NODE || only.contains(&c.node));
    }
    Ok(candidates)
}

/// `spec` with `sensors` in place of its own, validated.
///
/// # Errors
/// [`MachineError`] naming the bad sensor field.
pub fn with_sensors(
    spec: &MachineSpec,
    sensors: Vec<SensorSpec>,
) -> Result<MachineSpec, MachineError> {
    let mut s = spec.clone();
    s.sensors = sensors;
    s.validate("sensor set")?;
    Ok(s)
}

/// The study's default locations, as candidate names (the node each default sensor reads).
pub fn default_locations(spec: &MachineSpec) -> Vec<String> {
    let mut v: Vec<String> = vec![AMBIENT_NODE.into()];
    for s in &spec.sensors {
        if !v.contains(&s.node) {
            v.push(s.node.clone());
        }
    }
    v
}

/// The machine's own sensor locations ([`default_locations`]) that are not among `candidates`:
/// with any, the comparison leaves the "study default" set out.
pub fn defaults_not_candidates(spec: &MachineSpec, candidates: &[&str]) -> Vec<String> {
    default_locations(spec)
        .into_iter()
        .filter(|n| !candidates.contains(&n.as_str()))
        .collect()
}

/// Scenarios of the selection campaign: the typical calibration cycles (what the predictor is
/// trained on) followed by the selection-validation cycles of [`validation_cycles`].
pub fn selection_cycles(spec: &MachineSpec, seed: u64) -> Vec<ThermalCycle> {
    let mut v = ThermalCycle::calibration_plan(spec);
    v.extend(validation_cycles(seed, VALIDATION_STREAM));
    v
}

/// Atypical cycles the selection validates sensor sets on, drawn from stream `stream` of
/// `seed` (the selection uses stream 9001; never the evaluation's stream): random duty steps,
/// ambient steps, a sinusoidal ambient swing and a restart after a pause — the kinds of
/// variation the machine meets in service, with random speeds, durations, amplitudes and phases.
pub fn validation_cycles(seed: u64, stream: u64) -> Vec<ThermalCycle> {
    let mut state = sub_seed(seed, stream);
    let mut next = || {
        state = sub_seed(state, 1);
        (state >> 11) as f64 / (1u64 << 53) as f64
    };
    let phase = |hours: f64, rpm: f64, duty: f64| calibration::Phase {
        duration_s: hours * 3600.0,
        spindle_rpm: rpm,
        axis_speed_mm_per_min: [5000.0 * duty, 4000.0 * duty, 2500.0 * duty],
    };
    let rpm = |u: f64| 1000.0 + (u * 9.0).floor() * 1000.0;
    let mut v = Vec::new();
    // Random duty: 8 steps of 30 min, then 3 h of cooling.
    let mut phases: Vec<calibration::Phase> = (0..8)
        .map(|_| {
            let r = rpm(next());
            phase(0.5, r, next())
        })
        .collect();
    phases.push(phase(3.0, 0.0, 0.0));
    v.push(ThermalCycle {
        name: "sel_random_duty".into(),
        purpose: "selection validation".into(),
        soak_degc: None,
        ambient: AmbientProfile::Constant { temp_degc: 20.0 },
        phases,
    });
    // Ambient steps (air conditioning set points) over a heating and a cooling half.
    let up = 1.0 + 1.5 * next();
    let down = 1.0 + 2.0 * next();
    let r = rpm(next());
    let d = 0.3 + 0.7 * next();
    v.push(ThermalCycle {
        name: "sel_ambient_steps".into(),
        purpose: "selection validation".into(),
        soak_degc: None,
        ambient: AmbientProfile::Table {
            points: vec![
                [0.0, 20.0],
                [2.0 * 3600.0, 20.0],
                [2.5 * 3600.0, 20.0 + up],
                [5.0 * 3600.0, 20.0 + up],
                [5.5 * 3600.0, 20.0 - down],
                [8.0 * 3600.0, 20.0 - down],
            ],
        },
        phases: vec![phase(4.0, r, d), phase(4.0, 0.0, 0.0)],
    });
    // Sinusoidal ambient swing (day/night or a door), random amplitude, period and phase.
    let amplitude_degc = 1.0 + 1.5 * next();
    let period_s = (6.0 + 8.0 * next()) * 3600.0;
    let phase_rad = std::f64::consts::TAU * next();
    let r = rpm(next());
    let d = 0.3 + 0.7 * next();
    let hours_on = 3.0 + 2.0 * next();
    v.push(ThermalCycle {
        name: "sel_ambient_swing".into(),
        purpose: "selection validation".into(),
        soak_degc: None,
        ambient: AmbientProfile::Sinusoid {
            mean_degc: 19.5 + next(),
            amplitude_degc,
            period_s,
            phase_rad,
        },
        phases: vec![phase(hours_on, r, d), phase(8.0 - hours_on, 0.0, 0.0)],
    });
    // Restart: heat, pause while still warm, restart at another speed, cool.
    let (r1, d1, h1) = (rpm(next()), 0.3 + 0.7 * next(), 1.5 + next());
    let h2 = 1.0 + next();
    let (r2, d2, h3) = (rpm(next()), 0.3 + 0.7 * next(), 1.5 + next());
    v.push(ThermalCycle {
        name: "sel_restart".into(),
        purpose: "selection validation".into(),
        soak_degc: None,
        ambient: AmbientProfile::Constant { temp_degc: 20.0 },
        phases: vec![
            phase(h1, r1, d1),
            phase(h2, 0.0, 0.0),
            phase(h3, r2, d2),
            phase(2.0, 0.0, 0.0),
        ],
    });
    v
}

/// Stream of the selection-validation cycles (never the evaluation's).
const VALIDATION_STREAM: u64 = 9001;

/// The states at which the selection validates each proposed set: a cold machine, and each
/// selection-validation cycle ([`validation_cycles`] of the selection seed) after 2, 4 and 6 h.
/// None is a held-out evaluation state.
pub fn validation_states(seed: u64) -> Vec<EvalState> {
    let cycles = validation_cycles(seed, VALIDATION_STREAM);
    let mut v = vec![EvalState {
        name: "cold".into(),
        cycle: cycles[0].clone(),
        at_s: 0.0,
    }];
    for c in cycles {
        for h in [2.0, 4.0, 6.0] {
            v.push(EvalState {
                name: format!("{}@{h}h", c.name),
                cycle: c.clone(),
                at_s: h * 3600.0,
            });
        }
    }
    v
}

/// Compensation quality of one sensor set on the held-out runs.
#[derive(Debug, Clone, Serialize)]
pub struct SetResult {
    /// `selected`, `study default`, `random #i`, `all candidates`.
    pub label: String,
    /// The sensors (candidate names, reference first).
    pub sensors: Vec<String>,
    /// Held-out runs (diagonals × states × seeds).
    pub runs: usize,
    /// Median of 1 − RMS|E| after / before over the runs.
    pub median_reduction: f64,
    /// Worst run's reduction.
    pub worst_reduction: f64,
    /// Largest residual |E| at any point, µm.
    pub max_residual_um: f64,
    /// Mean over runs of RMS|E| after compensation, µm.
    pub mean_rms_after_um: f64,
    /// Quadratic mean over runs of RMS|E| after compensation, µm: the selection's validation
    /// score (a bad run weighs more than in the mean).
    pub qmean_rms_after_um: f64,
}

/// The whole study.
#[derive(Debug, Clone)]
pub struct PlacementReport {
    /// Names of the selection scenarios.
    pub scenarios: Vec<String>,
    /// The selection with its evidence.
    pub selection: Selection,
    /// Validation of each proposal ([`Selection::proposals`], same order) on the
    /// selection-validation states ([`validation_states`]).
    pub validation: Vec<SetResult>,
    /// Index of the chosen proposal: the lowest validation score.
    pub chosen: usize,
    /// The sensor specs of the selected set (reference first), ready for a machine file.
    pub selected_sensors: Vec<SensorSpec>,
    /// The comparison (empty without compare seeds).
    pub comparison: Vec<SetResult>,
}

/// Runs the placement study on `spec` (see the module doc).
///
/// # Errors
/// [`PlacementError`] from the campaign, selection or evaluation.
pub fn study(spec: &MachineSpec, cfg: &PlacementConfig) -> Result<PlacementReport, PlacementError> {
    study_among(spec, cfg, None)
}

/// [`study()`] restricted to the candidate nodes `only` (ambient always stays a candidate).
///
/// # Errors
/// As [`study()`].
pub fn study_among(
    spec: &MachineSpec,
    cfg: &PlacementConfig,
    only: Option<&[String]>,
) -> Result<PlacementReport, PlacementError> {
    let stage = selection_stage(spec, cfg, only)?;
    let mut rep = stage.report.clone();
    if !cfg.compare_seeds.is_empty() {
        let runs = compare_seeds(&stage, cfg, &cfg.compare_seeds)?;
        rep.comparison = summarise_comparison(&stage.sets, &runs);
    }
    Ok(rep)
}

/// What the selection stage leaves for the comparison: the report without its comparison, the
/// compared sensor sets, and the candidates' machine and selection data they train on.
#[derive(Debug, Clone)]
pub struct SelectionStage {
    /// The study so far ([`PlacementReport::comparison`] empty).
    pub report: PlacementReport,
    /// The compared sets in report order: label (`selected`, `study default` when its
    /// locations are all candidates, `random #i`, `all candidates`) and candidate names.
    pub sets: Vec<(String, Vec<String>)>,
    /// The machine with every candidate as a sensor.
    cand_spec: MachineSpec,
    /// The candidates.
    candidates: Vec<SensorSpec>,
    /// The typical cycles of the selection campaign (the comparison's data on the selection
    /// seed).
    typical: Dataset,
}

/// The selection stage of [`study_among`]: the selection campaign on `cfg.seed`, the proposals,
/// their validation, the choice and the sets to compare. Every comparison seed depends on it.
///
/// # Errors
/// As [`study()`].
pub fn selection_stage(
    spec: &MachineSpec,
    cfg: &PlacementConfig,
    only: Option<&[String]>,
) -> Result<SelectionStage, PlacementError> {
    let candidates = candidates_among(spec, only)?;
    let cand_spec = with_sensors(spec, candidates.clone())?;
    let scenarios = selection_cycles(spec, cfg.seed);
    let data = calibration::calibrate(&cand_spec, &scenarios, &CampaignConfig::new(cfg.seed))
        .map_err(EvalError::from)?;
    let selection = selection::select_sensors(&data, &cfg.selection)?;
    let typical = typical_part(spec, &data);
    let plans = campaign::diagonal_plans(&cand_spec)?;
    let states = validation_states(cfg.seed);
    let mut validation: Vec<SetResult> = Vec::new();
    for p in &selection.proposals {
        let mut key = p.sensors.clone();
        key.sort();
        let earlier = validation.iter().find(|v| {
            let mut k = v.sensors.clone();
            k.sort();
            k == key
        });
        let result = match earlier {
            Some(v) => SetResult {
                label: p.rule.name().into(),
                sensors: p.sensors.clone(),
                ..v.clone()
            },
            None => {
                let runs = evaluate_set(
                    &cand_spec,
                    &candidates,
                    &p.sensors,
                    cfg.seed,
                    &typical,
                    &states,
                    &plans,
                    &cfg.settings,
                )?;
                summarise(p.rule.name(), &p.sensors, &runs)
            }
        };
        validation.push(result);
    }
    let chosen = choose(&validation);
    let names = selection.proposals[chosen].sensors.clone();
    let selected_sensors: Vec<SensorSpec> = names
        .iter()
        .filter_map(|n| candidates.iter().find(|c| &c.name == n).cloned())
        .collect();

    let mut sets: Vec<(String, Vec<String>)> = vec![("selected".into(), names.clone())];
    // The machine's own locations are compared when they are all candidates; a restricted
    // candidate list may leave some out (the report says so: [`defaults_not_candidates`]).
    let cand_names: Vec<&str> = candidates.iter().map(|c| c.name.as_str()).collect();
    if defaults_not_candidates(spec, &cand_names).is_empty() {
        sets.push(("study default".into(), default_locations(spec)));
    }
    let pool: Vec<String> = candidates
        .iter()
        .map(|c| c.name.clone())
        .filter(|n| !cfg.selection.reference.contains(n))
        .collect();
    let mut rng = StdRng::seed_from_u64(sub_seed(cfg.seed, 9100));
    for i in 0..cfg.random_draws {
        let mut p = pool.clone();
        p.shuffle(&mut rng);
        let set: Vec<String> = cfg
            .selection
            .reference
            .iter()
            .cloned()
            .chain(p.into_iter().take(cfg.selection.count))
            .collect();
        sets.push((format!("random #{}", i + 1), set));
    }
    sets.push((
        "all candidates".into(),
        candidates.iter().map(|c| c.name.clone()).collect(),
    ));

    let report = PlacementReport {
        scenarios: scenarios.iter().map(|c| c.name.clone()).collect(),
        selection,
        validation,
        chosen,
        selected_sensors,
        comparison: Vec::new(),
    };
    Ok(SelectionStage {
        report,
        sets,
        cand_spec,
        candidates,
        typical,
    })
}

/// The typical (calibration) cycles of a selection dataset: what the predictor trains on.
fn typical_part(spec: &MachineSpec, data: &Dataset) -> Dataset {
    let cal: Vec<String> = ThermalCycle::calibration_plan(spec)
        .into_iter()
        .map(|c| c.name)
        .collect();
    let mut d = data.clone();
    d.records.retain(|r| cal.contains(&r.cycle));
    d
}

/// The proposal with the lowest validation score (the first of equals).
fn choose(validation: &[SetResult]) -> usize {
    validation
        .iter()
        .enumerate()
        .min_by(|a, b| a.1.qmean_rms_after_um.total_cmp(&b.1.qmean_rms_after_um))
        .map_or(0, |(i, _)| i)
}

/// Trains the hybrid predictor with the sensors `names` on `data` (machine `seed`) and runs
/// every diagonal of `plans` at every state with compensation.
#[allow(clippy::too_many_arguments)]
fn evaluate_set(
    cand_spec: &MachineSpec,
    candidates: &[SensorSpec],
    names: &[String],
    seed: u64,
    data: &Dataset,
    states: &[EvalState],
    plans: &[(&str, vmc_machine::motion::Plan)],
    settings: &Settings,
) -> Result<Vec<RunReport>, PlacementError> {
    let sensors: Vec<SensorSpec> = names
        .iter()
        .filter_map(|n| candidates.iter().find(|c| &c.name == n).cloned())
        .collect();
    let set_spec = with_sensors(cand_spec, sensors)?;
    let settings = campaign::fit_to_data(
        campaign::with_history_features(
            Settings {
                seed,
                sensors: names.to_vec(),
                ..settings.clone()
            },
            &set_spec,
        ),
        data,
    );
    let (hybrid, _) =
        predictor::train_hybrid(data, &set_spec.geometry(), &settings).map_err(EvalError::from)?;
    Ok(campaign::evaluate_predictor(
        &set_spec,
        seed,
        ModelKind::Hybrid,
        &hybrid,
        states,
        plans,
    )?)
}

/// The summary of one set over its runs (in the order given: the mean and quadratic mean sum
/// in that order).
pub fn summarise(label: &str, names: &[String], runs: &[RunReport]) -> SetResult {
    let mut red: Vec<f64> = runs.iter().map(|r| r.reduction).collect();
    SetResult {
        label: label.to_string(),
        sensors: names.to_vec(),
        runs: runs.len(),
        median_reduction: campaign::median(&mut red).unwrap_or(f64::NAN),
        worst_reduction: runs
            .iter()
            .map(|r| r.reduction)
            .fold(f64::INFINITY, f64::min),
        max_residual_um: runs.iter().map(|r| r.max_after_um).fold(0.0, f64::max),
        mean_rms_after_um: runs.iter().map(|r| r.rms_after_um).sum::<f64>()
            / runs.len().max(1) as f64,
        qmean_rms_after_um: (runs.iter().map(|r| r.rms_after_um.powi(2)).sum::<f64>()
            / runs.len().max(1) as f64)
            .sqrt(),
    }
}

/// A sensor set file: `[[sensors]]` entries, as in a machine file.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SensorSet {
    /// The sensors, in predictor order.
    pub sensors: Vec<SensorSpec>,
}

impl SensorSet {
    /// TOML text with a header comment (the file `select-sensors` writes).
    pub fn to_toml(&self, header: &str) -> String {
        let body = toml::to_string(self).unwrap_or_default();
        let mut s = String::new();
        for line in header.lines() {
            s.push_str("# ");
            s.push_str(line);
            s.push('\n');
        }
        s.push('\n');
        s.push_str(&body);
        s
    }

    /// Parses a sensor set file; `path` names it in errors.
    ///
    /// # Errors
    /// [`MachineError::Parse`] with the TOML location.
    pub fn from_toml_str(text: &str, path: &str) -> Result<Self, MachineError> {
        toml::from_str(text).map_err(|e| MachineError::Parse {
            path: path.to_string(),
            msg: e.to_string(),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_node_and_ambient_is_a_candidate_with_the_machines_thermistor_model() {
        let spec = MachineSpec::reference();
        let c = candidate_sensors(&spec).unwrap();
        assert_eq!(c.len(), spec.thermal.nodes.len() + 1);
        assert_eq!(c[0].node, AMBIENT_NODE);
        let t = spec
            .sensors
            .iter()
            .find(|s| s.node != AMBIENT_NODE)
            .unwrap();
        assert!(c[1..]
            .iter()
            .all(|s| s.noise_sigma_degc == t.noise_sigma_degc
                && s.time_constant_s == t.time_constant_s
                && s.resolution_degc == t.resolution_degc));
        with_sensors(&spec, c).unwrap();
    }

    #[test]
    fn selection_scenarios_are_not_evaluation_states() {
        let spec = MachineSpec::reference();
        let sel: Vec<String> = selection_cycles(&spec, 1)
            .iter()
            .map(|c| c.name.clone())
            .collect();
        for s in calibration::evaluation_states(&spec, 1) {
            assert!(!sel.contains(&s.cycle.name), "{} is held out", s.cycle.name);
        }
    }

    #[test]
    fn validation_states_are_selection_only_and_the_lowest_score_is_chosen() {
        let spec = MachineSpec::reference();
        let held_out: Vec<String> = calibration::evaluation_states(&spec, 1)
            .into_iter()
            .map(|s| s.cycle.name)
            .collect();
        let states = validation_states(1);
        assert_eq!(states.len(), 13);
        for s in &states {
            assert!(s.cycle.name.starts_with("sel_"), "{}", s.name);
            assert!(!held_out.contains(&s.cycle.name));
        }
        // Another seed draws other speeds, amplitudes and durations.
        assert_ne!(validation_cycles(1, 9001), validation_cycles(2, 9001));
        let r = |q: f64| SetResult {
            label: String::new(),
            sensors: Vec::new(),
            runs: 1,
            median_reduction: 0.9,
            worst_reduction: 0.9,
            max_residual_um: 1.0,
            mean_rms_after_um: q,
            qmean_rms_after_um: q,
        };
        assert_eq!(choose(&[r(1.2), r(0.8), r(0.9), r(0.8)]), 1);
    }

    #[test]
    fn the_default_locations_are_the_reference_machines_nodes() {
        // Ambient first, then every node a sensor of the machine reads, each once.
        let check = |spec: &MachineSpec| {
            let d = default_locations(spec);
            assert_eq!(d[0], AMBIENT_NODE, "{d:?}");
            let mut once = d.clone();
            once.sort();
            once.dedup();
            assert_eq!(once.len(), d.len(), "a location twice: {d:?}");
            for s in &spec.sensors {
                assert!(d.contains(&s.node), "{} missing from {d:?}", s.node);
            }
            assert!(d[1..]
                .iter()
                .all(|n| spec.sensors.iter().any(|s| &s.node == n)));
            d
        };
        let spec = MachineSpec::reference();
        let d = check(&spec);
        // A second sensor on a node and no sensor in the air change neither rule.
        let mut other = spec.clone();
        other.sensors.retain(|s| s.node != AMBIENT_NODE);
        let mut twin_sensor = other.sensors[0].clone();
        twin_sensor.name.push_str("_2");
        other.sensors.push(twin_sensor);
        assert_eq!(check(&other), d);
    }

    #[test]
    fn a_sensor_set_file_round_trips_and_rejects_unknown_fields() {
        let spec = MachineSpec::reference();
        let set = SensorSet {
            sensors: spec.sensors.clone(),
        };
        let text = set.to_toml("test");
        let back = SensorSet::from_toml_str(&text, "s.toml").unwrap();
        assert_eq!(back.sensors, set.sensors);
        let bad = text.replace("noise_sigma_degc", "noise_sigma");
        let e = SensorSet::from_toml_str(&bad, "s.toml")
            .unwrap_err()
            .to_string();
        assert!(e.contains("s.toml") && e.contains("noise_sigma"), "{e}");
    }
}
