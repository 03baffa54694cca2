//! The comparison stage of the placement study (see [`super`]): for each compare seed, one
//! calibration on the typical cycles, then every compared set trained on it and evaluated on
//! every diagonal under the held-out states. The seeds are independent of each other, which is
//! what `select-sensors --shard` splits; the summaries are computed over the runs of all seeds
//! in the order of the compare seeds ([`summarise_comparison`]), so a split run and its merge
//! give the same figures to the bit.

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use super::{evaluate_set, summarise, PlacementConfig, PlacementError, SelectionStage, SetResult};
use crate::predict::dataset::Dataset;
use crate::studies::calibration::{self, CampaignConfig, ThermalCycle};
use crate::studies::campaign::{self, EvalError, RunReport};

/// The held-out runs of every compared set on one machine seed.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct SeedRuns {
    /// The machine seed.
    pub seed: u64,
    /// One list of runs per compared set, in the order of [`SelectionStage::sets`].
    pub runs: Vec<Vec<RunReport>>,
}

/// Runs the comparison of `stage`'s sets on the machine seeds `seeds` (a part of
/// `cfg.compare_seeds`, or all of it), one [`SeedRuns`] per seed in the order given. The
/// calibrations of the seeds run in parallel; the selection seed reuses the typical cycles of
/// the selection campaign.
///
/// # Errors
/// Calibration, training or evaluation errors.
pub fn compare_seeds(
    stage: &SelectionStage,
    cfg: &PlacementConfig,
    seeds: &[u64],
) -> Result<Vec<SeedRuns>, PlacementError> {
    let cand_spec = &stage.cand_spec;
    let cal = ThermalCycle::calibration_plan(cand_spec);
    let plans = campaign::diagonal_plans(cand_spec)?;
    // One calibration dataset per seed, with every candidate logged; each set trains on its
    // columns. The selection seed's typical cycles are part of the selection data.
    let datasets: Vec<Dataset> = seeds
        .par_iter()
        .map(|&seed| {
            if seed == cfg.seed {
                Ok(stage.typical.clone())
            } else {
                calibration::calibrate(cand_spec, &cal, &CampaignConfig::new(seed))
                    .map_err(EvalError::from)
            }
        })
        .collect::<Result<_, EvalError>>()?;
    let mut out = Vec::with_capacity(seeds.len());
    for (&seed, data) in seeds.iter().zip(&datasets) {
        let states = calibration::evaluation_states(cand_spec, seed);
        let mut runs = Vec::with_capacity(stage.sets.len());
        for (_, names) in &stage.sets {
            runs.push(evaluate_set(
                cand_spec,
                &stage.candidates,
                names,
                seed,
                data,
                &states,
                &plans,
                &cfg.settings,
            )?);
        }
        out.push(SeedRuns { seed, runs });
    }
    Ok(out)
}

/// The comparison's summary of each set over the runs of every seed of `seeds`, taken in that
/// order (the order of the compare seeds).
pub fn summarise_comparison(sets: &[(String, Vec<String>)], seeds: &[SeedRuns]) -> Vec<SetResult> {
    sets.iter()
        .enumerate()
        .map(|(k, (label, names))| {
            let runs: Vec<RunReport> = seeds
                .iter()
                .flat_map(|s| s.runs.get(k).into_iter().flatten().cloned())
                .collect();
            summarise(label, names, &runs)
        })
        .collect()
}
