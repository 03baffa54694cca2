//! The static-table study: what a compensation table fixed at one thermal state carries against
//! a machine that warms up, next to the live hybrid, on the campaign's held-out runs.
//!
//! **The tables.** For each machine seed, the campaign's trained hybrid is brought to a
//! *freezing state* by following the sensor readings and the commanded duty of a twin driven
//! through it (as `export --warmup` does; knowledge side only: the model sees readings and
//! what was commanded, never the twin's truth), then sampled into tables
//! (`vmc_tables::sample`, the export's default 10 mm spacing). The freezing states are stated
//! before any held-out run is looked at, both from the calibration plan (training-like):
//!
//! - *cold*: the start of `cal_4000_8000rpm`, the machine at rest at the shop's 20 °C;
//! - *warm*: `cal_4000_8000rpm` after 2 h at 4000 rpm with combined duty (the hours can be
//!   chosen, within the cycle's 8 h).
//!
//! The twin that leads the model to a freezing state is the seed's machine with noise from its
//! own streams (`8000 + i`: neither the calibration's `1000 + k` nor the evaluation's `5000 + …`).
//!
//! **The runs.** Each table set is applied as a controller applies it
//! (`vmc_tables::apply::TableCompensator`: per-joint tables alone, or own-axis and cross tables)
//! on every diagonal at every held-out state, with the very same machine and noise seeds as the
//! campaign's hybrid runs ([`campaign::eval_noise_seed`]): the runs compare point by point with
//! the live hybrid's. Figures: reduction of RMS |E| and max residual |E| per run, as the campaign
//! reports them ([`run_report`]).

use rayon::prelude::*;
use serde::Serialize;
use thiserror::Error;

use crate::predict::predictor::{HybridPredictor, ModelKind};
use crate::studies::calibration::{self, EvalState, ThermalCycle};
use crate::studies::campaign::{
    self, run_report, units, CampaignProgress, EvalError, RunReport, TrainedModels,
};
use vmc_machine::machine::MachineSpec;
use vmc_machine::motion::Plan;
use vmc_machine::twin::{sub_seed, Twin, TwinError};
use vmc_tables::apply::{TableCompensator, TableScope};
use vmc_tables::sample::{sample_tables, AxisTravel, SampleError, SamplingSpec, TableSet};

pub use summary::{write_static_tables, write_static_tables_json, StudyFigures, VariantFigures};

mod summary;

/// The file the study writes in the campaign's output folder.
pub const STATIC_TABLES_FILE: &str = "static-tables.json";

/// The calibration cycle both freezing states are taken from.
pub const FREEZE_CYCLE: &str = "cal_4000_8000rpm";

/// Default hours into [`FREEZE_CYCLE`] of the warm freezing state: the end of its 4000 rpm
/// phase.
pub const DEFAULT_WARM_H: f64 = 2.0;

/// First noise stream of the twins that lead the model to the freezing states.
const FREEZE_NOISE_STREAM: u64 = 8000;

/// The table scopes, in report order.
pub const SCOPES: [TableScope; 2] = [TableScope::OwnAxis, TableScope::OwnAndCross];

/// A study that could not run.
#[derive(Debug, Error)]
pub enum TablesError {
    /// The held-out runs could not run.
    #[error(transparent)]
    Eval(#[from] EvalError),
    /// A twin problem on the way to a freezing state.
    #[error(transparent)]
    Twin(#[from] TwinError),
    /// The tables could not be sampled.
    #[error("sampling the tables frozen {frozen} for seed {seed}: {source}")]
    Sample {
        /// The freezing state.
        frozen: String,
        /// Machine seed.
        seed: u64,
        /// What went wrong.
        source: SampleError,
    },
    /// A warm freezing state outside the freezing cycle.
    #[error(
        "the warm freezing state must be within the {cycle_h} h of {FREEZE_CYCLE} (0 < HOURS ≤ \
         {cycle_h}), got {hours}"
    )]
    WarmHours {
        /// Hours asked for.
        hours: f64,
        /// The cycle's length, h.
        cycle_h: f64,
    },
    /// The calibration plan has no freezing cycle (a changed plan).
    #[error("the calibration plan has no cycle {FREEZE_CYCLE} to freeze the tables at")]
    NoFreezeCycle,
}

/// A thermal state the tables are frozen at.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Freezing {
    /// `cold` or `warm`.
    pub name: String,
    /// The calibration cycle.
    pub cycle: String,
    /// Hours into it.
    pub at_h: f64,
    /// In words.
    pub description: String,
}

/// The freezing states: cold (0 h) and warm (`warm_h` into [`FREEZE_CYCLE`]), each with the
/// state the twin is driven to.
///
/// # Errors
/// `warm_h` not within the cycle, or no such cycle in the plan.
pub fn freezing_states(warm_h: f64) -> Result<Vec<(Freezing, EvalState)>, TablesError> {
    let cycle = ThermalCycle::combined_duty_set()
        .into_iter()
        .find(|c| c.name == FREEZE_CYCLE)
        .ok_or(TablesError::NoFreezeCycle)?;
    let cycle_h = cycle.duration_s() / 3600.0;
    if !(warm_h.is_finite() && warm_h > 0.0 && warm_h <= cycle_h) {
        return Err(TablesError::WarmHours {
            hours: warm_h,
            cycle_h,
        });
    }
    let phase = cycle.phase_at(warm_h * 3600.0 - 1e-6);
    let warm_words = format!(
        "{FREEZE_CYCLE} at {warm_h} h (running at {:.0} rpm, axes at {:.0}/{:.0}/{:.0} mm/min)",
        phase.spindle_rpm,
        phase.axis_speed_mm_per_min[0],
        phase.axis_speed_mm_per_min[1],
        phase.axis_speed_mm_per_min[2]
    );
    Ok([
        (
            "cold",
            0.0,
            format!("{FREEZE_CYCLE} at 0 h (cold start, at rest)"),
        ),
        ("warm", warm_h, warm_words),
    ]
    .into_iter()
    .map(|(name, at_h, description)| {
        let f = Freezing {
            name: name.into(),
            cycle: FREEZE_CYCLE.into(),
            at_h,
            description,
        };
        let state = EvalState {
            name: format!("{FREEZE_CYCLE}@{at_h}h"),
            cycle: cycle.clone(),
            at_s: at_h * 3600.0,
        };
        (f, state)
    })
    .collect())
}

/// The tables' sampling: the machine's travel, the export's defaults.
pub fn sampling_spec(spec: &MachineSpec) -> SamplingSpec {
    let axes = &spec.axes;
    SamplingSpec::new(std::array::from_fn(|k| AxisTravel {
        min_mm: axes.travel_min_mm[k],
        max_mm: axes.travel_max_mm[k],
    }))
}

/// The tables of `hybrid` frozen at `state` on machine `seed` (the `index`-th freezing state,
/// which picks the twin's noise stream): the model follows the twin's readings and commanded
/// duty up to the state, then is sampled.
///
/// # Errors
/// The twin's, or tables that cannot be sampled.
pub fn freeze_tables(
    spec: &MachineSpec,
    seed: u64,
    index: usize,
    frozen: &str,
    state: &EvalState,
    hybrid: &HybridPredictor,
) -> Result<TableSet, TablesError> {
    let mut model = model_at_freezing(spec, seed, index, state, hybrid)?;
    sample_tables(&mut model, &sampling_spec(spec)).map_err(|source| TablesError::Sample {
        frozen: frozen.into(),
        seed,
        source,
    })
}

/// `hybrid` after following the readings and the commanded duty of machine `seed` up to
/// `state`, the `index`-th freezing state (its twin's noise stream): the model the tables of
/// that state are sampled from.
///
/// # Errors
/// The twin's.
pub fn model_at_freezing(
    spec: &MachineSpec,
    seed: u64,
    index: usize,
    state: &EvalState,
    hybrid: &HybridPredictor,
) -> Result<HybridPredictor, TwinError> {
    let noise = sub_seed(seed, FREEZE_NOISE_STREAM + index as u64);
    let mut twin = Twin::with_noise_seed(spec, seed, noise)?;
    state.cycle.prepare(&mut twin)?;
    campaign::follow_to_state(&mut twin, state, hybrid.clone())
}

/// Runs every diagonal of `plans` at every state of `states` on machine `seed` with the tables
/// of `scope` from `tables` in the loop, with the campaign's evaluation noise seeds; in
/// parallel, results in (state, diagonal) order. The runs carry the hybrid's kind (the
/// tables' source).
///
/// # Errors
/// The simulation's.
pub fn evaluate_tables(
    spec: &MachineSpec,
    seed: u64,
    tables: &TableSet,
    scope: TableScope,
    states: &[EvalState],
    plans: &[(&str, Plan)],
    progress: &dyn CampaignProgress,
) -> Result<Vec<RunReport>, EvalError> {
    let jobs: Vec<(usize, usize)> = (0..states.len())
        .flat_map(|si| (0..plans.len()).map(move |di| (si, di)))
        .collect();
    let results: Vec<Result<Option<RunReport>, EvalError>> = jobs
        .par_iter()
        .map(|&(si, di)| {
            let (state, (diag, plan)) = (&states[si], &plans[di]);
            let noise = campaign::eval_noise_seed(seed, si, di);
            let mut ctrl = TableCompensator::new(tables.clone(), scope);
            let points =
                calibration::run_at_state(spec, seed, noise, state, plan, Some(&mut ctrl))?;
            progress.advance(
                units::RUN,
                &format!(
                    "seed {seed}: {} tables {diag} at {}",
                    scope.name(),
                    state.name
                ),
            );
            Ok(run_report(
                ModelKind::Hybrid,
                diag,
                &state.name,
                seed,
                &points,
            ))
        })
        .collect();
    let mut out = Vec::with_capacity(results.len());
    for r in results {
        out.extend(r?);
    }
    Ok(out)
}

/// A table set frozen for one seed, and what it loses against the model at its own state.
#[derive(Debug, Clone, Serialize)]
pub struct FrozenTables {
    /// Machine seed.
    pub seed: u64,
    /// The freezing state's name.
    pub frozen: String,
    /// The model's error at the tables' reference position, µm.
    pub reference_error_um: [f64; 3],
    /// The model's reversal per axis, µm.
    pub reversal_um: [f64; 3],
    /// The tables against the model over the volume, at the freezing state.
    pub volume: vmc_tables::sample::VolumeCheck,
}

/// The study's runs: each a table variant's (or the live hybrid's).
#[derive(Debug, Clone)]
pub struct StaticTableStudy {
    /// The freezing states.
    pub freezing: Vec<Freezing>,
    /// Row names: the table variants (scope × freezing state), then the live hybrid.
    pub variants: Vec<String>,
    /// Every run, with its variant's index in [`Self::variants`].
    pub runs: Vec<(usize, RunReport)>,
    /// The table sets, per seed and freezing state.
    pub tables: Vec<FrozenTables>,
}

/// The name of a table variant.
pub fn variant_name(scope: TableScope, frozen: &str) -> String {
    format!("{}, frozen {frozen}", scope.name())
}

/// The name of the live hybrid's row.
pub const LIVE_HYBRID: &str = "live hybrid";

/// Runs the study on the campaign's trained hybrids (`models`), next to the campaign's hybrid
/// runs `hybrid_runs` (the live hybrid's row; any other predictor's runs are left out).
///
/// # Errors
/// A bad warm freezing state, the simulation's, tables that cannot be sampled.
pub fn run_static_table_study(
    spec: &MachineSpec,
    models: &[TrainedModels],
    hybrid_runs: &[RunReport],
    warm_h: f64,
    progress: &dyn CampaignProgress,
) -> Result<StaticTableStudy, TablesError> {
    let freezing = freezing_states(warm_h)?;
    let plans = campaign::diagonal_plans(spec)?;
    let n_runs = (calibration::evaluation_states(spec, 0).len() * plans.len()) as u64;
    let variants_per_seed = (SCOPES.len() * freezing.len()) as u64;
    progress.add_total(models.len() as u64 * variants_per_seed * n_runs * units::RUN);
    let mut variants: Vec<String> = SCOPES
        .iter()
        .flat_map(|s| freezing.iter().map(|(f, _)| variant_name(*s, &f.name)))
        .collect();
    let live = variants.len();
    variants.push(LIVE_HYBRID.into());
    let per_seed: Vec<Result<SeedStudy, TablesError>> = models
        .par_iter()
        .map(|m| seed_study(spec, m, &freezing, &plans, progress))
        .collect();
    let mut study = StaticTableStudy {
        freezing: freezing.into_iter().map(|(f, _)| f).collect(),
        variants,
        runs: Vec::new(),
        tables: Vec::new(),
    };
    for r in per_seed {
        let (tables, runs) = r?;
        study.tables.extend(tables);
        study.runs.extend(runs);
    }
    study.runs.extend(
        hybrid_runs
            .iter()
            .filter(|r| r.predictor == ModelKind::Hybrid)
            .map(|r| (live, r.clone())),
    );
    Ok(study)
}

/// One seed's table sets and its runs, each with its variant's index.
type SeedStudy = (Vec<FrozenTables>, Vec<(usize, RunReport)>);

/// The table sets and runs of one seed: variant `s·F + f` for scope `s` frozen at state `f`.
fn seed_study(
    spec: &MachineSpec,
    m: &TrainedModels,
    freezing: &[(Freezing, EvalState)],
    plans: &[(&str, Plan)],
    progress: &dyn CampaignProgress,
) -> Result<SeedStudy, TablesError> {
    let states = calibration::evaluation_states(spec, m.seed);
    let mut tables = Vec::new();
    let mut runs = Vec::new();
    for (fi, (f, state)) in freezing.iter().enumerate() {
        progress.advance(0, &format!("seed {}: tables frozen {}", m.seed, f.name));
        let set = freeze_tables(spec, m.seed, fi, &f.name, state, &m.hybrid)?;
        for (si, scope) in SCOPES.iter().enumerate() {
            let variant = si * freezing.len() + fi;
            let r = evaluate_tables(spec, m.seed, &set, *scope, &states, plans, progress)?;
            runs.extend(r.into_iter().map(|r| (variant, r)));
        }
        tables.push(FrozenTables {
            seed: m.seed,
            frozen: f.name.clone(),
            reference_error_um: set.reference_error_mm.map(|e| e * 1e3),
            reversal_um: set.reversal_shift_mm.map(|e| e * 1e3),
            volume: set.volume,
        });
    }
    Ok((tables, runs))
}
