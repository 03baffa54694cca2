//! The printed campaign summary and `report.json`, both built from parts that can also come
//! one at a time: a [`ReportHeader`] (the set-up), the training summaries and the runs. The
//! whole campaign in memory and a merge of shard results streamed from files go through the
//! same two functions ([`write_summary`] over a [`SummaryDigest`], [`write_report_json`]), so
//! they print and write the same bytes.

use std::io::Write;

use serde::{Deserialize, Serialize};

use crate::predict::predictor::ModelKind;

use super::fleet::{write_fleet_summary, Fleet};
use super::report::{
    headline_of, CampaignReport, Headline, PlannedCycle, RunDigest, RunReport, PREDICTORS,
    WARM_RUN_MIN_THERMAL_UM,
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

/// What the printed summary needs of a campaign: the header and a [`RunDigest`] per run, fed
/// one run at a time.
#[derive(Debug, Clone)]
pub struct SummaryDigest {
    /// The set-up.
    pub header: ReportHeader,
    /// Diagonal names in the order of their first run.
    pub diagonals: Vec<String>,
    /// Thermal state names in the order of their first run.
    pub states: Vec<String>,
    /// One digest per run, in run order.
    pub runs: Vec<RunDigest>,
    /// The machines' figures (the fleet section).
    pub fleet: Fleet,
}

impl SummaryDigest {
    /// An empty digest of the campaign set up as `header`.
    pub fn new(header: ReportHeader) -> Self {
        Self {
            header,
            diagonals: Vec::new(),
            states: Vec::new(),
            runs: Vec::new(),
            fleet: Fleet::default(),
        }
    }

    /// The digest of a whole report.
    pub fn of(rep: &CampaignReport) -> Self {
        let mut d = Self::new(rep.header());
        for r in &rep.runs {
            d.push(r);
        }
        d
    }

    /// Adds a run.
    pub fn push(&mut self, r: &RunReport) {
        let diagonal = intern(&mut self.diagonals, &r.diagonal);
        let state = intern(&mut self.states, &r.thermal_state);
        self.fleet.push(r);
        self.runs.push(RunDigest {
            diagonal,
            state,
            ..RunDigest::of(r)
        });
    }
}

/// Position of `name` in `names`, appended when new.
fn intern(names: &mut Vec<String>, name: &str) -> u16 {
    let at = names.iter().position(|n| n == name).unwrap_or_else(|| {
        names.push(name.to_string());
        names.len() - 1
    });
    u16::try_from(at).unwrap_or(u16::MAX)
}

/// Writes what a person reads first for a campaign in memory: see [`write_summary`].
///
/// # Errors
/// The writer's.
pub fn write_campaign_summary(rep: &CampaignReport, out: &mut dyn Write) -> std::io::Result<()> {
    write_summary(&SummaryDigest::of(rep), out)
}

/// Writes what a person reads first: the campaign's set-up, the headline figures per predictor,
/// then median reduction and max residual per predictor × diagonal and per predictor × thermal
/// state.
///
/// # Errors
/// The writer's.
pub fn write_summary(d: &SummaryDigest, out: &mut dyn Write) -> std::io::Result<()> {
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
    for p in PREDICTORS {
        if let Some(h) = headline_of(&d.runs, p) {
            writeln!(out, "  {:<10} runs {:>4}  median reduction {:>5.1} %  worst run {:>5.1} %  max residual |E| {:>5.2} µm  worst residual/thermal part {:>5.1} %  mean prediction RMSE {:>5.2} µm",
                p.name(), h.runs, h.median_reduction * 100.0, h.worst_reduction * 100.0, h.max_after_um,
                h.worst_residual_share.unwrap_or(f64::NAN) * 100.0, h.mean_rmse_um)?;
        }
    }
    let diagonals: Vec<(&str, Option<u16>)> = d
        .diagonals
        .iter()
        .enumerate()
        .map(|(k, n)| (n.as_str(), u16::try_from(k).ok()))
        .collect();
    let states: Vec<(&str, Option<u16>)> = rep
        .evaluation_states
        .iter()
        .map(|s| {
            let at = d.states.iter().position(|n| n == s);
            (s.as_str(), at.and_then(|k| u16::try_from(k).ok()))
        })
        .collect();
    writeln!(out, "by diagonal: median reduction % / max residual |E| µm")?;
    write_aggregate(d, out, &diagonals, |r, g| Some(r.diagonal) == g)?;
    writeln!(
        out,
        "by thermal state: median reduction % / max residual |E| µm / worst residual share of the thermal part %"
    )?;
    write_aggregate(d, out, &states, |r, g| Some(r.state) == g)?;
    writeln!(out, "(reduction = 1 − RMS|E'|/RMS|E| of a run, E' compensated; residual share = RMS|E'| / RMS of the error's thermal part, on warm runs (thermal part ≥ {WARM_RUN_MIN_THERMAL_UM} µm RMS); every run: --runs, or report.json)")?;
    write_fleet_summary(&d.fleet, out)
}

/// One table: a row per group, a column per predictor, each cell `median red % / max |E'| µm`
/// over the runs of the group.
fn write_aggregate(
    d: &SummaryDigest,
    out: &mut dyn Write,
    groups: &[(&str, Option<u16>)],
    in_group: impl Fn(&RunDigest, Option<u16>) -> bool,
) -> std::io::Result<()> {
    let label = groups.iter().map(|g| g.0.len()).max().unwrap_or(0);
    let predictors: Vec<ModelKind> = PREDICTORS
        .into_iter()
        .filter(|p| d.runs.iter().any(|r| r.predictor == *p))
        .collect();
    write!(out, "  {:<label$}", "")?;
    for p in &predictors {
        write!(out, " {:>19}", p.name())?;
    }
    writeln!(out)?;
    for (g, at) in groups {
        write!(out, "  {g:<label$}")?;
        for p in &predictors {
            let cell = Headline::of_digests(
                d.runs
                    .iter()
                    .filter(|r| r.predictor == *p && in_group(r, *at)),
            )
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
