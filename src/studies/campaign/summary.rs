//! The printed campaign summary and `report.json`, both built from parts that can also come
//! one at a time: a [`ReportHeader`] (the set-up), the training summaries and the runs. The
//! whole campaign in memory and a merge of shard results streamed from files go through the
//! same builder and writers ([`SummaryBuilder`] → [`Summary`] → [`write_summary`], and
//! [`write_report_json`]), so they print and write the same bytes.

use std::io::Write;

use serde::{Deserialize, Serialize};

use crate::predict::predictor::ModelKind;

use super::fleet::{write_fleet_summary, FleetBuilder, FleetSummary};
use super::order_stats::StreamChanged;
use super::report::{
    replay, CampaignReport, Headline, HeadlineBuilder, PlannedCycle, RunPasses, RunReport,
    PREDICTORS, WARM_RUN_MIN_THERMAL_UM,
};

/// Everything in a campaign report but the training summaries and the runs.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ReportHeader {
    /// Machine name.
    pub machine: String,
    /// Calibration cycles (used for training).
    pub calibration_cycles: Vec<String>,
    /// The calibration plan: each cycle's machine time and purpose.
    pub calibration_plan: Vec<PlannedCycle>,
    /// Held-out evaluation states.
    pub evaluation_states: Vec<String>,
    /// Whether the hybrid used the commanded spindle speed.
    pub hybrid_uses_spindle_speed: bool,
}

impl CampaignReport {
    /// The report's header.
    pub fn header(&self) -> ReportHeader {
        ReportHeader {
            machine: self.machine.clone(),
            calibration_cycles: self.calibration_cycles.clone(),
            calibration_plan: self.calibration_plan.clone(),
            evaluation_states: self.evaluation_states.clone(),
            hybrid_uses_spindle_speed: self.hybrid_uses_spindle_speed,
        }
    }
}

/// The layout of `report.json`: [`CampaignReport`]'s fields in its order, with the training
/// summaries and runs as anything that serialises as a sequence (a slice, or a stream).
#[derive(Serialize)]
struct ReportFile<'a, T, R> {
    machine: &'a str,
    calibration_cycles: &'a [String],
    calibration_plan: &'a [PlannedCycle],
    evaluation_states: &'a [String],
    training: T,
    runs: R,
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    hybrid_uses_spindle_speed: bool,
}

/// Writes `report.json` (pretty JSON) from its header, the training summaries (a sequence of
/// `(seed, TrainSummary)`) and the runs (a sequence of [`RunReport`]).
///
/// # Errors
/// The writer's, or the sequences' own serialisation errors.
pub fn write_report_json<T: Serialize, R: Serialize>(
    header: &ReportHeader,
    training: T,
    runs: R,
    out: impl std::io::Write,
) -> serde_json::Result<()> {
    serde_json::to_writer_pretty(
        out,
        &ReportFile {
            machine: &header.machine,
            calibration_cycles: &header.calibration_cycles,
            calibration_plan: &header.calibration_plan,
            evaluation_states: &header.evaluation_states,
            training,
            runs,
            hybrid_uses_spindle_speed: header.hybrid_uses_spindle_speed,
        },
    )
}

/// The headline figures of one group of runs for each of the [`PREDICTORS`].
type PerPredictor<T> = [T; 3];

/// Position of a predictor in [`PREDICTORS`].
fn predictor_index(p: ModelKind) -> usize {
    PREDICTORS.iter().position(|&q| q == p).unwrap_or(0)
}

/// Everything the printed summary says, computed.
#[derive(Debug, Clone)]
pub struct Summary {
    /// The set-up.
    pub header: ReportHeader,
    /// Headline per predictor over all runs (None: the predictor has no run).
    pub overall: PerPredictor<Option<Headline>>,
    /// Per diagonal (in the order of their first run): its headline per predictor.
    pub by_diagonal: Vec<(String, PerPredictor<Option<Headline>>)>,
    /// Per thermal state (in the order of their first run): its headline per predictor.
    pub by_state: Vec<(String, PerPredictor<Option<Headline>>)>,
    /// The machines' figures (the fleet section).
    pub fleet: FleetSummary,
}

/// Builds a [`Summary`] from the runs of a campaign, fed in passes ([`RunPasses`]). The campaign replays its runs from memory, the merge reads them again from the
/// shards' files; either way the memory does not grow with the runs (the medians and
/// percentiles are exact order statistics found over the passes, see
/// [`super::order_stats`]).
#[derive(Debug, Clone)]
pub struct SummaryBuilder {
    header: ReportHeader,
    keep_max: usize,
    /// Passes ended.
    passes: u32,
    overall: PerPredictor<HeadlineBuilder>,
    by_diagonal: Vec<(String, PerPredictor<HeadlineBuilder>)>,
    by_state: Vec<(String, PerPredictor<HeadlineBuilder>)>,
    fleet: FleetBuilder,
}

impl SummaryBuilder {
    /// An empty summary of the campaign set up as `header`.
    pub fn new(header: ReportHeader) -> Self {
        Self::with_keep_max(header, super::order_stats::KEEP_MAX)
    }

    /// The same, with order statistics keeping at most `keep_max` values per search (fewer:
    /// more passes; the figures are the same).
    pub fn with_keep_max(header: ReportHeader, keep_max: usize) -> Self {
        let group = || std::array::from_fn(|_| HeadlineBuilder::with_keep_max(keep_max));
        Self {
            header,
            keep_max,
            passes: 0,
            overall: group(),
            by_diagonal: Vec::new(),
            by_state: Vec::new(),
            fleet: FleetBuilder::with_keep_max(keep_max),
        }
    }

    /// The summary (after the pass that said done).
    pub fn finish(self) -> Summary {
        let heads = |g: &PerPredictor<HeadlineBuilder>| -> PerPredictor<Option<Headline>> {
            std::array::from_fn(|k| g[k].finish())
        };
        Summary {
            overall: heads(&self.overall),
            by_diagonal: self
                .by_diagonal
                .iter()
                .map(|(n, g)| (n.clone(), heads(g)))
                .collect(),
            by_state: self
                .by_state
                .iter()
                .map(|(n, g)| (n.clone(), heads(g)))
                .collect(),
            fleet: self.fleet.finish(),
            header: self.header,
        }
    }
}

impl RunPasses for SummaryBuilder {
    /// Adds a run of the current pass.
    fn push(&mut self, r: &RunReport) {
        let p = predictor_index(r.predictor);
        let keep_max = self.keep_max;
        self.overall[p].push(r);
        group_of(&mut self.by_diagonal, &r.diagonal, keep_max)[p].push(r);
        group_of(&mut self.by_state, &r.thermal_state, keep_max)[p].push(r);
        self.fleet.push(r);
    }

    /// Ends a pass; true when the summary is complete.
    ///
    /// # Errors
    /// A pass over other runs than the first one.
    fn end_pass(&mut self) -> Result<bool, StreamChanged> {
        self.passes += 1;
        let mut done = self.fleet.end_pass()?;
        for h in self
            .overall
            .iter_mut()
            .chain(self.by_diagonal.iter_mut().flat_map(|g| g.1.iter_mut()))
            .chain(self.by_state.iter_mut().flat_map(|g| g.1.iter_mut()))
        {
            done &= h.end_pass()?;
        }
        Ok(done)
    }
}

/// The group named `name` (appended when new).
fn group_of<'a>(
    groups: &'a mut Vec<(String, PerPredictor<HeadlineBuilder>)>,
    name: &str,
    keep_max: usize,
) -> &'a mut PerPredictor<HeadlineBuilder> {
    let at = groups.iter().position(|g| g.0 == name).unwrap_or_else(|| {
        let group = std::array::from_fn(|_| HeadlineBuilder::with_keep_max(keep_max));
        groups.push((name.to_string(), group));
        groups.len() - 1
    });
    &mut groups[at].1
}

impl Summary {
    /// The summary of a campaign's runs in memory.
    pub fn of(header: ReportHeader, runs: &[RunReport]) -> Self {
        let mut b = SummaryBuilder::new(header);
        // The same runs in the same order: the passes agree.
        let _ = replay(&mut b, runs.iter());
        b.finish()
    }
}

/// Writes what a person reads first for a campaign in memory: see [`write_summary`].
///
/// # Errors
/// The writer's.
pub fn write_campaign_summary(rep: &CampaignReport, out: &mut dyn Write) -> std::io::Result<()> {
    write_summary(&Summary::of(rep.header(), &rep.runs), out)
}

/// Writes what a person reads first: the campaign's set-up, the headline figures per predictor,
/// then median reduction and max residual per predictor × diagonal and per predictor × thermal
/// state, then the fleet.
///
/// # Errors
/// The writer's.
pub fn write_summary(d: &Summary, out: &mut dyn Write) -> std::io::Result<()> {
    let rep = &d.header;
    let hours: f64 = rep.calibration_plan.iter().map(|c| c.hours).sum();
    writeln!(
        out,
        "vmc-twin campaign on {}: calibration plan of {} cycles, {hours:.0} machine hours per machine:",
        rep.machine,
        rep.calibration_plan.len(),
    )?;
    for c in &rep.calibration_plan {
        writeln!(out, "  {:<20} {:>4.1} h  {}", c.name, c.hours, c.purpose)?;
    }
    writeln!(
        out,
        "evaluated on held-out states {}",
        rep.evaluation_states.join(", ")
    )?;
    if rep.hybrid_uses_spindle_speed {
        writeln!(
            out,
            "hybrid: with the commanded spindle speed as heat input (--spindle-speed, opt-in)"
        )?;
    }
    writeln!(out, "summary over all diagonals, states and seeds:")?;
    for (p, h) in PREDICTORS.iter().zip(&d.overall) {
        if let Some(h) = h {
            writeln!(out, "  {:<10} runs {:>4}  median reduction {:>5.1} %  worst run {:>5.1} %  max residual |E| {:>5.2} µm  worst residual/thermal part {:>5.1} %  mean prediction RMSE {:>5.2} µm",
                p.name(), h.runs, h.median_reduction * 100.0, h.worst_reduction * 100.0, h.max_after_um,
                h.worst_residual_share.unwrap_or(f64::NAN) * 100.0, h.mean_rmse_um)?;
        }
    }
    let diagonals: Vec<(&str, Option<&PerPredictor<Option<Headline>>>)> = d
        .by_diagonal
        .iter()
        .map(|(n, g)| (n.as_str(), Some(g)))
        .collect();
    let states: Vec<(&str, Option<&PerPredictor<Option<Headline>>>)> = rep
        .evaluation_states
        .iter()
        .map(|s| {
            let g = d.by_state.iter().find(|g| g.0 == *s).map(|g| &g.1);
            (s.as_str(), g)
        })
        .collect();
    writeln!(
        out,
        "by diagonal: median reduction % / max residual |E| µm / worst residual share of the thermal part %"
    )?;
    write_aggregate(d, out, &diagonals)?;
    writeln!(
        out,
        "by thermal state: median reduction % / max residual |E| µm / worst residual share of the thermal part %"
    )?;
    write_aggregate(d, out, &states)?;
    writeln!(out, "(reduction = 1 − RMS|E'|/RMS|E| of a run, E' compensated; residual share = RMS|E'| / RMS of the error's thermal part, on warm runs (thermal part ≥ {WARM_RUN_MIN_THERMAL_UM} µm RMS); every run: --runs, or report.json)")?;
    write_fleet_summary(&d.fleet, out)
}

/// One table: a row per group, a column per predictor with runs, each cell
/// `median red % / max |E'| µm` over the runs of the group.
fn write_aggregate(
    d: &Summary,
    out: &mut dyn Write,
    groups: &[(&str, Option<&PerPredictor<Option<Headline>>>)],
) -> std::io::Result<()> {
    let label = groups.iter().map(|g| g.0.len()).max().unwrap_or(0);
    let predictors: Vec<usize> = (0..PREDICTORS.len())
        .filter(|&k| d.overall[k].is_some())
        .collect();
    write!(out, "  {:<label$}", "")?;
    for &k in &predictors {
        write!(out, " {:>19}", PREDICTORS[k].name())?;
    }
    writeln!(out)?;
    for (g, heads) in groups {
        write!(out, "  {g:<label$}")?;
        for &k in &predictors {
            let cell = heads
                .and_then(|h| h[k])
                .map(|h| match h.worst_residual_share {
                    Some(s) => format!(
                        "{:.1} / {:.2} / {:.0}",
                        h.median_reduction * 100.0,
                        h.max_after_um,
                        s * 100.0
                    ),
                    None => format!("{:.1} / {:.2}", h.median_reduction * 100.0, h.max_after_um),
                })
                .unwrap_or_else(|| "-".into());
            write!(out, " {cell:>19}")?;
        }
        writeln!(out)?;
    }
    Ok(())
}

/// One machine's part of a campaign: its three training summaries and its runs, in report
/// order. A shard writes one per line (`seeds.jsonl`); the merge reads them back exactly
/// (f64 round-trips through serde_json's shortest representation and its correctly rounded
/// parser).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct SeedResults {
    /// Machine seed.
    pub seed: u64,
    /// Training summaries of the seed, in [`PREDICTORS`] order.
    pub training: Vec<(u64, crate::predict::predictor::TrainSummary)>,
    /// The seed's runs, in report order.
    pub runs: Vec<RunReport>,
}

impl CampaignReport {
    /// The report's training summaries and runs, grouped by seed in `seeds` order.
    pub fn by_seed(&self, seeds: &[u64]) -> Vec<SeedResults> {
        seeds
            .iter()
            .map(|&seed| SeedResults {
                seed,
                training: self
                    .training
                    .iter()
                    .filter(|t| t.0 == seed)
                    .cloned()
                    .collect(),
                runs: self
                    .runs
                    .iter()
                    .filter(|r| r.seed == seed)
                    .cloned()
                    .collect(),
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A run with figures that vary with `i` (ties included).
    fn run(i: u32, predictor: ModelKind, seed: u64, diagonal: &str, state: &str) -> RunReport {
        let red = 0.85 + f64::from((i * 37) % 29) / 250.0;
        RunReport {
            predictor,
            diagonal: diagonal.into(),
            thermal_state: state.into(),
            seed,
            points: 10,
            rms_before_um: 10.0,
            rms_after_um: 10.0 * (1.0 - red),
            max_before_um: 20.0,
            max_after_um: 0.5 + f64::from((i * 13) % 31) / 10.0,
            reduction: red,
            max_reduction: 0.0,
            rms_before_xyz_um: [0.0; 3],
            rms_after_xyz_um: [0.0; 3],
            max_before_xyz_um: [5.0, 6.0, 7.0],
            max_after_xyz_um: [0.1, 0.3, 0.2],
            rms_thermal_um: Some(2.0),
            residual_share_of_thermal: i.is_multiple_of(3).then(|| f64::from(i % 7) / 50.0),
            mad_um: 0.0,
            mape: None,
            rmse_um: f64::from(i % 11) / 10.0,
            r2: None,
            samples: Vec::new(),
        }
    }

    #[test]
    fn the_printed_summary_does_not_depend_on_how_many_values_are_kept_per_pass() {
        let header = ReportHeader {
            machine: "m".into(),
            calibration_cycles: vec!["c".into()],
            calibration_plan: vec![PlannedCycle {
                name: "c".into(),
                hours: 2.0,
                purpose: "p".into(),
            }],
            evaluation_states: vec!["cold".into(), "warm".into(), "stress_z".into()],
            hybrid_uses_spindle_speed: false,
        };
        let mut runs = Vec::new();
        let mut i = 0;
        for seed in 1..=12 {
            for p in PREDICTORS {
                for state in ["cold", "warm", "stress_z"] {
                    for diagonal in ["XY", "YZ", "PPP", "NPP"] {
                        i += 1;
                        runs.push(run(i, p, seed, diagonal, state));
                    }
                }
            }
        }
        let text = |s: &Summary| {
            let mut v = Vec::new();
            write_summary(s, &mut v).unwrap();
            String::from_utf8(v).unwrap()
        };
        let whole = text(&Summary::of(header.clone(), &runs));
        let mut b = SummaryBuilder::with_keep_max(header, 3);
        let passes = replay(&mut b, runs.iter()).unwrap();
        assert!(passes > 2, "{passes} passes");
        assert_eq!(text(&b.finish()), whole);
        assert!(whole.contains("fleet of 12 machines"), "{whole}");
        // The headline median against a sorted copy of the hybrid's reductions.
        let mut red: Vec<f64> = runs
            .iter()
            .filter(|r| r.predictor == ModelKind::Hybrid)
            .map(|r| r.reduction)
            .collect();
        let m = crate::studies::campaign::median(&mut red).unwrap();
        assert!(whole.contains(&format!("median reduction {:>5.1} %", m * 100.0)));
    }
}
