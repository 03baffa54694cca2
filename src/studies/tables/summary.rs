//! The static-table study's figures: per variant over all runs and per held-out state, printed
//! as a table and written as `static-tables.json`.

use std::io::Write;

use serde::Serialize;

use super::{Freezing, FrozenTables, StaticTableStudy};
use crate::studies::campaign::{median, Headline, RunReport};

/// The figures of one variant over a set of runs.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct VariantFigures {
    /// The variant (`per-joint, frozen cold`, …, `live hybrid`).
    pub variant: String,
    /// Runs.
    pub runs: usize,
    /// Median of the runs' reductions of RMS |E| (fraction).
    pub median_reduction: f64,
    /// Smallest reduction of a run (fraction).
    pub worst_reduction: f64,
    /// Largest reduction of a run (fraction).
    pub best_reduction: f64,
    /// Median of the runs' RMS |E| after compensation, µm.
    pub median_rms_after_um: f64,
    /// Largest |E| after compensation over the runs, µm.
    pub max_after_um: f64,
    /// Largest residual share of the thermal part over the warm runs (fraction).
    pub worst_residual_share: Option<f64>,
}

impl VariantFigures {
    /// The figures of `runs` (None without runs).
    pub fn of<'a>(variant: &str, runs: impl IntoIterator<Item = &'a RunReport>) -> Option<Self> {
        let runs: Vec<&RunReport> = runs.into_iter().collect();
        let h = Headline::of(runs.iter().copied())?;
        let mut rms_after: Vec<f64> = runs.iter().map(|r| r.rms_after_um).collect();
        Some(Self {
            variant: variant.into(),
            runs: h.runs,
            median_reduction: h.median_reduction,
            worst_reduction: h.worst_reduction,
            best_reduction: runs
                .iter()
                .map(|r| r.reduction)
                .fold(f64::NEG_INFINITY, f64::max),
            median_rms_after_um: median(&mut rms_after)?,
            max_after_um: h.max_after_um,
            worst_residual_share: h.worst_residual_share,
        })
    }
}

/// Everything the study prints and writes.
#[derive(Debug, Clone, Serialize)]
pub struct StudyFigures {
    /// The freezing states.
    pub freezing: Vec<Freezing>,
    /// Per variant over all runs (a variant without runs is left out).
    pub overall: Vec<VariantFigures>,
    /// Per held-out state (in the order of the runs): per variant.
    pub by_state: Vec<(String, Vec<VariantFigures>)>,
    /// The table sets and what they lose against the model at their own state.
    pub tables: Vec<FrozenTables>,
}

impl StudyFigures {
    /// The figures of `study`.
    pub fn of(study: &StaticTableStudy) -> Self {
        let of_variant = |v: usize, state: Option<&str>| {
            VariantFigures::of(
                &study.variants[v],
                study
                    .runs
                    .iter()
                    .filter(|(i, r)| *i == v && state.is_none_or(|s| r.thermal_state == s))
                    .map(|(_, r)| r),
            )
        };
        let mut states: Vec<String> = Vec::new();
        for (_, r) in &study.runs {
            if !states.contains(&r.thermal_state) {
                states.push(r.thermal_state.clone());
            }
        }
        let n = study.variants.len();
        Self {
            freezing: study.freezing.clone(),
            overall: (0..n).filter_map(|v| of_variant(v, None)).collect(),
            by_state: states
                .iter()
                .map(|s| {
                    let f = (0..n).filter_map(|v| of_variant(v, Some(s))).collect();
                    (s.clone(), f)
                })
                .collect(),
            tables: study.tables.clone(),
        }
    }
}

/// Prints the study: the freezing states, the figures per variant, the median reduction and
/// max residual per held-out state.
///
/// # Errors
/// The writer's.
pub fn write_static_tables(f: &StudyFigures, out: &mut dyn Write) -> std::io::Result<()> {
    writeln!(
        out,
        "static tables (sampled from each seed's hybrid at a freezing state, 10 mm apart, then \
         held) against the live hybrid, on the same held-out runs:"
    )?;
    for z in &f.freezing {
        writeln!(out, "  frozen {:<5} {}", z.name, z.description)?;
    }
    writeln!(
        out,
        "  {:<24} {:>5} {:>9} {:>9} {:>9} {:>10} {:>10} {:>10}",
        "", "runs", "median %", "worst %", "best %", "med RMS|E'|", "max |E'|", "res/th %"
    )?;
    for v in &f.overall {
        writeln!(
            out,
            "  {:<24} {:>5} {:>9.1} {:>9.1} {:>9.1} {:>11.2} {:>10.2} {:>10.0}",
            v.variant,
            v.runs,
            v.median_reduction * 100.0,
            v.worst_reduction * 100.0,
            v.best_reduction * 100.0,
            v.median_rms_after_um,
            v.max_after_um,
            v.worst_residual_share.unwrap_or(f64::NAN) * 100.0
        )?;
    }
    writeln!(
        out,
        "by thermal state: median reduction % / max residual |E| µm"
    )?;
    let heads: Vec<String> = f
        .overall
        .iter()
        .map(|v| format!("{:>16}", v.variant.replace(", frozen", "")))
        .collect();
    writeln!(out, "  {:<24}{}", "", heads.join(""))?;
    for (state, vs) in &f.by_state {
        let cells: Vec<String> = vs
            .iter()
            .map(|v| {
                let cell = format!("{:.1} / {:.2}", v.median_reduction * 100.0, v.max_after_um);
                format!("{cell:>16}")
            })
            .collect();
        writeln!(out, "  {state:<24}{}", cells.join(""))?;
    }
    writeln!(
        out,
        "(reduction = 1 − RMS|E'|/RMS|E| of a run; per-joint = each axis's own table, forward or \
         reverse column by direction of motion (LinuxCNC COMP_FILE); own+cross = with the cross \
         tables (Siemens CEC); res/th = RMS|E'| / RMS of the thermal part on warm runs; every \
         run: static-tables.json with --out)"
    )
}

/// Writes `static-tables.json` (pretty JSON): the figures and every run with its variant.
///
/// # Errors
/// The writer's or serialisation's.
pub fn write_static_tables_json(
    f: &StudyFigures,
    study: &StaticTableStudy,
    out: impl Write,
) -> serde_json::Result<()> {
    #[derive(Serialize)]
    struct Run<'a> {
        variant: &'a str,
        #[serde(flatten)]
        run: &'a RunReport,
    }
    #[derive(Serialize)]
    struct File<'a> {
        #[serde(flatten)]
        figures: &'a StudyFigures,
        runs: Vec<Run<'a>>,
    }
    let runs = study
        .runs
        .iter()
        .map(|(v, run)| Run {
            variant: &study.variants[*v],
            run,
        })
        .collect();
    serde_json::to_writer_pretty(out, &File { figures: f, runs })
}
